//! SHA-256 (FIPS 180-4) of a file's bytes, so a report names exactly the data it fitted.
//! Computed by the `sha2` crate; the digest is written as 64 lower-case hex digits.

use sha2::{Digest, Sha256};

/// The SHA-256 digest of `data` as 64 lower-case hex digits.
#[cfg(test)]
pub(crate) fn sha256_hex(data: &[u8]) -> String {
    hex(Sha256::digest(data).as_slice())
}

/// The SHA-256 digest of everything `reader` yields, read in 64 KiB pieces (a big file is
/// never held whole), and the number of bytes read.
pub(crate) fn sha256_hex_of(mut reader: impl std::io::Read) -> std::io::Result<(String, u64)> {
    let mut h = Sha256::new();
    let mut buf = vec![0u8; 1 << 16];
    let mut len = 0u64;
    loop {
        match reader.read(&mut buf) {
            Ok(0) => break,
            Ok(k) => {
                h.update(&buf[..k]);
                len += k as u64;
            }
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok((hex(h.finalize().as_slice()), len))
}

/// `bytes` as lower-case hex, two digits per byte.
fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

#[cfg(test)]
mod tests {
    use super::{sha256_hex, sha256_hex_of};

    #[test]
    fn fips_180_vectors() {
        assert_eq!(
            sha256_hex(b"abc"),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
        assert_eq!(
            sha256_hex(b""),
            "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855"
        );
        assert_eq!(
            sha256_hex(b"abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1"
        );
    }

    #[test]
    fn pieces_of_any_size_give_the_digest_of_the_whole() {
        // 1000 × 'a' crosses block and padding boundaries; the reader hands out pieces of
        // 7 bytes.
        let data = vec![b'a'; 1000];
        struct Pieces<'a>(&'a [u8]);
        impl std::io::Read for Pieces<'_> {
            fn read(&mut self, out: &mut [u8]) -> std::io::Result<usize> {
                let k = self.0.len().min(7).min(out.len());
                out[..k].copy_from_slice(&self.0[..k]);
                self.0 = &self.0[k..];
                Ok(k)
            }
        }
        let (hex, len) = sha256_hex_of(Pieces(&data)).unwrap();
        assert_eq!(len, 1000);
        assert_eq!(hex, sha256_hex(&data));
        assert_eq!(
            hex,
            "41edece42d63e8d9bf515a9ba6932e1c20cbc9f5a5d134645adb5db1b9737ea3"
        );
    }

    #[test]
    fn a_million_a_read_in_64_kib_pieces() {
        // FIPS 180-2 appendix B.3: one million 'a', more than fifteen reads of the buffer.
        let data = vec![b'a'; 1_000_000];
        let (hex, len) = sha256_hex_of(&data[..]).unwrap();
        assert_eq!(len, 1_000_000);
        assert_eq!(
            hex,
            "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0"
        );
    }
}
