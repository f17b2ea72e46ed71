//! Input and output: atomic file writing (no half-written outputs), and readers/writers of the
//! formats gearbif exchanges with other programs.

pub mod full_disk;
pub mod outdir;
pub mod outfiles;
pub mod recordings;
pub mod workdir;

pub use outdir::StagedDir;
pub use outfiles::{FileKind, StagedFiles};
pub use workdir::WorkDir;

use crate::error::{Error, Result};
use std::path::Path;

/// Writes `bytes` to `path` atomically: to a temporary file beside it, then renamed over it, so a
/// reader (or a killed run) never sees a half-written file.
pub fn write_atomic(path: impl AsRef<Path>, bytes: &[u8]) -> Result<()> {
    let path = path.as_ref();
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    if !dir.exists() {
        std::fs::create_dir_all(dir).map_err(|e| Error::file("create", dir, e))?;
    }
    let name = path.file_name().ok_or_else(|| {
        Error::option(
            format!("output path {}", path.display()),
            "is not a file path (it ends in `..` or is a root)",
        )
    })?;
    let tmp = dir.join(format!(
        ".{}.tmp-{}",
        name.to_string_lossy(),
        std::process::id()
    ));
    if let Err(e) = full_disk::write(&tmp, bytes) {
        let _ = std::fs::remove_file(&tmp);
        return Err(Error::file("write", &tmp, e));
    }
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        Error::file("move into place", path, e)
    })
}

/// Removes from `dir` the temporary files of [`write_atomic`] (`.NAME.tmp-PID`) whose process is
/// gone: what a killed run leaves behind. Files of a live process are kept (it may still rename
/// them); where liveness cannot be checked (not Linux), nothing is removed.
pub fn remove_stale_temporaries(dir: &Path) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let name = e.file_name();
        let name = name.to_string_lossy();
        let Some(pid) = temporary_pid(&name) else {
            continue;
        };
        if cfg!(target_os = "linux")
            && pid != std::process::id()
            && !Path::new("/proc").join(pid.to_string()).exists()
        {
            let _ = std::fs::remove_file(e.path());
        }
    }
}

/// The process id in the name of a hidden temporary file or folder of this crate's writers
/// (`.NAME.tmp-PID`, `.NAME.tmp-PID.EXT`, `.tmp-PID-N.png`), `None` for any other name.
pub fn temporary_pid(name: &str) -> Option<u32> {
    let (_, rest) = name
        .strip_prefix('.')?
        .rsplit_once(".tmp-")
        .or_else(|| name.strip_prefix(".tmp-").map(|r| ("", r)))?;
    let digits = rest.split(|c: char| !c.is_ascii_digit()).next()?;
    digits.parse().ok()
}

/// Serialises `value` as pretty JSON and writes it atomically.
pub fn write_json_atomic<T: serde::Serialize>(path: impl AsRef<Path>, value: &T) -> Result<()> {
    let path = path.as_ref();
    let s = serde_json::to_string_pretty(value)
        .map_err(|e| Error::format("JSON", path.display().to_string(), e))?;
    write_atomic(path, s.as_bytes())
}

/// A JSON output with its versioned schema id as first field: `{"schema": "gearbif.map/1", …}`
/// followed by the fields of `value` (docs/formats.md lists every schema).
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct Schema<'a, T: serde::Serialize> {
    /// The schema id, `gearbif.<name>/<version>`.
    pub schema: &'static str,
    /// The output; its fields are written beside `schema`.
    #[serde(flatten)]
    pub value: &'a T,
}

/// Tags `value` (a struct or map) with the schema id `schema`.
pub fn with_schema<'a, T: serde::Serialize>(schema: &'static str, value: &'a T) -> Schema<'a, T> {
    Schema { schema, value }
}

#[cfg(test)]
mod tests {
    #[test]
    fn atomic_write_replaces_file() {
        let dir = std::env::temp_dir().join(format!("gearbif-io-{}", std::process::id()));
        let p = dir.join("sub/out.txt");
        super::write_atomic(&p, b"one").unwrap();
        super::write_atomic(&p, b"two").unwrap();
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "two");
        let leftovers = std::fs::read_dir(p.parent().unwrap()).unwrap().count();
        assert_eq!(leftovers, 1);
        std::fs::remove_dir_all(dir).ok();
    }
}
