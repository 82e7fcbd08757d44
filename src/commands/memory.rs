//! How the command's allocator hands memory back to the system.

/// A big fit's columns (8 bytes per sample each) are allocated and freed in turn: the
/// table as read, the prepared geometry, fitted values, residuals and the adequacy tests'
/// temporaries. glibc's allocator gives each buffer of at least its mmap threshold its own
/// mapping, returned to the system when freed, but after freeing one it raises the
/// threshold to that buffer's size (up to 32 MiB), so that later buffers of a few MB come
/// from its per-thread heaps, where freed space stays resident and is not always reused.
/// Fixing the threshold at 256 KiB keeps the process's resident memory at what its live
/// columns need; the trim threshold of 2 MiB (fixed with it, else 128 KiB) keeps the
/// small buffers of an evaluation's blocks in the heaps between evaluations instead of
/// mapping them afresh. Buffers of small fits (a texel's 66 samples, a 10,000-sample scan)
/// stay below both.
pub(crate) fn return_big_buffers() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only sets parameters of the allocator; it is called before any
    // thread is started.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 256 * 1024);
        libc::mallopt(libc::M_TRIM_THRESHOLD, 2 * 1024 * 1024);
    }
}
