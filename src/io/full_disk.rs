//! A simulated full disk, for tests of the failure paths of output writing: with
//! `GEARBIF_FAIL_WRITE=N` in the environment, the N-th output file this process writes (1-based,
//! counting every file of [`crate::io::write_atomic`] and every PNG of `plotting::save`) receives
//! half of its bytes and then fails with `ENOSPC` ("No space left on device"), the error a write
//! on a full filesystem returns. Everything after the failing write runs as it would on a real
//! full disk: the same error value reaches the same callers. Without the variable nothing fails.

use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::OnceLock;

/// The environment variable naming the write that fails.
pub const VAR: &str = "GEARBIF_FAIL_WRITE";

/// ENOSPC on Linux and macOS.
const ENOSPC: i32 = 28;

fn failing_write() -> Option<u64> {
    static N: OnceLock<Option<u64>> = OnceLock::new();
    *N.get_or_init(|| std::env::var(VAR).ok().and_then(|v| v.trim().parse().ok()))
}

/// True if the write being started is the one that fails (see the module documentation).
fn this_write_fails() -> bool {
    static COUNT: AtomicU64 = AtomicU64::new(0);
    let Some(n) = failing_write() else {
        return false;
    };
    COUNT.fetch_add(1, Ordering::SeqCst) + 1 == n
}

/// Writes `bytes` to the new file `path`: `std::fs::write`, or, for the failing write, half of
/// the bytes followed by `ENOSPC`.
pub fn write(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    if this_write_fails() {
        std::fs::write(path, &bytes[..bytes.len() / 2])?;
        return Err(std::io::Error::from_raw_os_error(ENOSPC));
    }
    std::fs::write(path, bytes)
}

/// For a file another library has written (a PNG): for the failing write, cuts it to half its
/// length and returns `ENOSPC`, as if the disk had filled while it was written.
pub fn after_external_write(path: &Path) -> std::io::Result<()> {
    if this_write_fails() {
        let len = std::fs::metadata(path)?.len();
        std::fs::OpenOptions::new()
            .write(true)
            .open(path)?
            .set_len(len / 2)?;
        return Err(std::io::Error::from_raw_os_error(ENOSPC));
    }
    Ok(())
}
