//! The RGL "tensor_file" container: a header listing named, typed n-dimensional fields
//! and their data offsets, all little-endian.
//!
//! ```text
//! bytes 0..12   "tensor_file\0"
//! bytes 12..14  version: 1, 0
//! bytes 14..18  field count (u32)
//! per field:    name length (u16), name (UTF-8), ndim (u16), dtype (u8),
//!               data offset (u64), shape (ndim × u64)
//! ```
//!
//! dtype codes: 1 uint8, 2 int8, 3 uint16, 4 int16, 5 uint32, 6 int32, 7 uint64, 8 int64,
//! 9 float16, 10 float32, 11 float64. Every error names the field (or header part), its
//! byte offset and what was expected; nothing in a file makes parsing panic or allocate
//! more than the file's own size.

/// The dtype code of a 32-bit float field.
pub(crate) const FLOAT32: u8 = 10;

/// The magic bytes a tensor file starts with.
pub(crate) const MAGIC: &[u8; 12] = b"tensor_file\0";

/// One field of a tensor file: where its header and its data are.
#[derive(Debug, Clone)]
pub(crate) struct Field {
    /// The field's name as stored (UTF-8).
    pub name: String,
    /// Byte offset of the field's header entry.
    pub header_at: usize,
    /// Its element type code (see the module doc; [`FLOAT32`], …).
    pub dtype: u8,
    /// Byte offset of the data.
    pub offset: usize,
    /// Its size along each dimension, outermost first (the element count is their product).
    pub shape: Vec<usize>,
}

/// A parsed tensor file over its bytes.
#[derive(Debug)]
pub(crate) struct TensorFile<'a> {
    bytes: &'a [u8],
    /// The fields in the order the header lists them.
    pub fields: Vec<Field>,
}

/// Bytes per element of a dtype code (0 for an unknown code).
fn dtype_size(dtype: u8) -> usize {
    match dtype {
        1 | 2 => 1,
        3 | 4 | 9 => 2,
        5 | 6 | 10 => 4,
        7 | 8 | 11 => 8,
        _ => 0,
    }
}

/// A dtype code as a name, for messages.
pub(crate) fn dtype_name(dtype: u8) -> String {
    let names = [
        "invalid", "uint8", "int8", "uint16", "int16", "uint32", "int32", "uint64", "int64",
        "float16", "float32", "float64",
    ];
    names
        .get(dtype as usize)
        .map_or_else(|| format!("unknown dtype code {dtype}"), |s| s.to_string())
}

/// A little-endian cursor whose reads fail with the byte offset and what was being read.
struct Cursor<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Cursor<'a> {
    fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], String> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.bytes.len());
        match end {
            Some(end) => {
                let s = &self.bytes[self.at..end];
                self.at = end;
                Ok(s)
            }
            None => Err(format!(
                "byte {}: {what}: expected {n} bytes, the file ends after {}",
                self.at,
                self.bytes.len() - self.at.min(self.bytes.len())
            )),
        }
    }
    fn u16(&mut self, what: &str) -> Result<u16, String> {
        Ok(u16::from_le_bytes(self.take(2, what)?.try_into().unwrap()))
    }
    fn u32(&mut self, what: &str) -> Result<u32, String> {
        Ok(u32::from_le_bytes(self.take(4, what)?.try_into().unwrap()))
    }
    fn u64(&mut self, what: &str) -> Result<u64, String> {
        Ok(u64::from_le_bytes(self.take(8, what)?.try_into().unwrap()))
    }
}

/// Whether `bytes` start like a tensor file (the magic).
pub(crate) fn is_tensor_file(bytes: &[u8]) -> bool {
    bytes.starts_with(MAGIC)
}

impl<'a> TensorFile<'a> {
    /// Parse the header and check that every field's data lies within the file. The error
    /// text (without the path) names the byte offset, the field and what was expected.
    pub(crate) fn parse(bytes: &'a [u8]) -> Result<TensorFile<'a>, String> {
        let mut c = Cursor { bytes, at: 0 };
        let magic = c.take(12, "magic")?;
        if magic != MAGIC {
            return Err(
                "byte 0: magic: expected \"tensor_file\\0\" (not an RGL .bsdf tensor file)".into(),
            );
        }
        let version = c.take(2, "version")?;
        if version != [1, 0] {
            return Err(format!(
                "byte 12: version: expected 1.0, found {}.{}",
                version[0], version[1]
            ));
        }
        let count = c.u32("field count")? as usize;
        // The smallest field entry is 13 bytes: a count the file cannot hold is refused
        // before anything is allocated for it.
        if count == 0 || count > (bytes.len() - c.at) / 13 {
            return Err(format!(
                "byte 14: field count: {count} fields cannot fit in the {} bytes left",
                bytes.len() - c.at
            ));
        }
        let mut fields = Vec::with_capacity(count);
        for _ in 0..count {
            fields.push(parse_field(&mut c)?);
        }
        Ok(TensorFile { bytes, fields })
    }

    /// The field called `name`, or an error saying which fields there are.
    pub(crate) fn field(&self, name: &str) -> Result<&Field, String> {
        self.fields.iter().find(|f| f.name == name).ok_or_else(|| {
            let names: Vec<&str> = self.fields.iter().map(|f| f.name.as_str()).collect();
            format!(
                "field '{name}' is missing (fields: {}): not an RGL BRDF file",
                names.join(", ")
            )
        })
    }

    /// The raw bytes of a field's data (bounds checked at parse time).
    pub(crate) fn data(&self, f: &Field) -> &'a [u8] {
        let n: usize = f.shape.iter().product::<usize>() * dtype_size(f.dtype);
        &self.bytes[f.offset..f.offset + n]
    }

    /// A float32 field's values.
    pub(crate) fn f32_values(&self, f: &Field) -> Vec<f32> {
        self.data(f)
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes(b.try_into().unwrap()))
            .collect()
    }
}

/// One header entry; its data must lie within the file.
fn parse_field(c: &mut Cursor) -> Result<Field, String> {
    let header_at = c.at;
    let name_len = c.u16("field name length")? as usize;
    let name_bytes = c.take(name_len, "field name")?;
    let name = String::from_utf8_lossy(name_bytes).into_owned();
    let what = |part: &str| format!("field '{name}' (entry at byte {header_at}): {part}");
    let ndim = c.u16(&what("ndim"))? as usize;
    let dtype = c.take(1, &what("dtype"))?[0];
    if dtype_size(dtype) == 0 {
        return Err(format!(
            "byte {}: {}: expected a dtype code 1..=11, found {dtype}",
            c.at - 1,
            what("dtype")
        ));
    }
    let offset = c.u64(&what("data offset"))?;
    let mut shape = Vec::new();
    let mut total = dtype_size(dtype) as u128;
    for _ in 0..ndim {
        let n = c.u64(&what("shape"))?;
        total = total.saturating_mul(n as u128);
        shape.push(n as usize);
    }
    let len = c.bytes.len() as u128;
    if (offset as u128).saturating_add(total) > len {
        return Err(format!(
            "byte {header_at}: field '{name}': its data ({total} bytes at offset {offset}, shape {shape:?}) lies beyond the end of the file ({len} bytes)"
        ));
    }
    Ok(Field {
        name,
        header_at,
        dtype,
        offset: offset as usize,
        shape,
    })
}
