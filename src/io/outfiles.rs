//! Output files named by flags (`--out x.json --plot x.svg`), written as one result: the plan is
//! checked before the work (no two flags name one file, no file is an existing folder, a figure
//! ends in `.svg` or `.png`, and a file can be created in each target's folder: a read-only mount
//! is found here); the work writes each file under a hidden name beside its target
//! (`.STEM.tmp-PID.EXT`); [`StagedFiles::commit`] renames them into place at the end. A run that
//! fails removes every staged file (and the folders it created for them), so the targets stay as
//! they were; a killed run leaves only hidden temporaries, removed by the next run writing into
//! the same folder.

use crate::error::{Error, Result};
use std::path::{Path, PathBuf};

/// What an output file holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FileKind {
    /// Data (CSV, JSON): any name.
    Data,
    /// A figure: the name ends in `.svg` or `.png`.
    Figure,
}

/// One planned output file.
#[derive(Debug)]
struct Planned {
    target: PathBuf,
    staged: PathBuf,
}

/// Output files being written (see the module documentation).
#[derive(Debug)]
pub struct StagedFiles {
    files: Vec<Planned>,
    created: Vec<PathBuf>,
    committed: bool,
}

/// `.STEM.tmp-PID.EXT` beside `target` (the extension kept: the figure writer picks its format
/// by it).
fn staged_name(target: &Path) -> PathBuf {
    let stem = target.file_stem().unwrap_or_default().to_string_lossy();
    let pid = std::process::id();
    let name = match target.extension() {
        Some(e) => format!(".{stem}.tmp-{pid}.{}", e.to_string_lossy()),
        None => format!(".{stem}.tmp-{pid}"),
    };
    target.with_file_name(name)
}

/// The folder of `path` (`.` for a bare name).
fn folder_of(path: &Path) -> &Path {
    path.parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."))
}

/// Refuses `path` (given by `flag`) as an output file of kind `kind`.
fn check_one(flag: &str, path: &Path, kind: FileKind) -> Result<()> {
    let what = || format!("{flag} {}", path.display());
    if path.is_dir() || path.file_name().is_none() {
        return Err(Error::option(what(), "is a folder, expected a file"));
    }
    if kind == FileKind::Figure {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        if !matches!(ext.as_deref(), Some("svg" | "png")) {
            return Err(Error::option(what(), "a figure must end in .svg or .png"));
        }
    }
    crate::io::outdir::check_ancestors(flag, folder_of(path))
}

/// A file's identity for the collision check: its folder made absolute (symbolic links
/// resolved where it exists) and its name.
fn identity(path: &Path) -> PathBuf {
    let dir = folder_of(path);
    let dir = dir.canonicalize().unwrap_or_else(|_| {
        std::env::current_dir()
            .map(|c| c.join(dir))
            .unwrap_or(dir.to_path_buf())
    });
    dir.join(path.file_name().unwrap_or_default())
}

impl StagedFiles {
    /// Checks the plan `(flag, path, kind)` and creates the missing folders (see the module
    /// documentation).
    pub fn begin(plan: &[(&str, &Path, FileKind)]) -> Result<Self> {
        for (i, &(flag, path, kind)) in plan.iter().enumerate() {
            check_one(flag, path, kind)?;
            if let Some((other, _, _)) = plan[..i]
                .iter()
                .find(|(_, p, _)| identity(p) == identity(path))
            {
                return Err(Error::inconsistent(
                    format!("{other}, {flag}"),
                    format!("both name the file {}", path.display()),
                ));
            }
        }
        let mut s = Self {
            files: Vec::new(),
            created: Vec::new(),
            committed: false,
        };
        for &(_, path, _) in plan {
            s.prepare(path)?;
        }
        Ok(s)
    }

    /// Creates the folder of `path` if missing, checks a file can be created there (removing the
    /// stale temporaries of killed runs), and plans the staged file.
    fn prepare(&mut self, path: &Path) -> Result<()> {
        let dir = folder_of(path);
        if let Some(c) = crate::io::outdir::create_missing(dir)? {
            self.created.push(c);
        }
        crate::io::remove_stale_temporaries(dir);
        let staged = staged_name(path);
        std::fs::write(&staged, b"").map_err(|e| Error::file("write", &staged, e))?;
        let _ = std::fs::remove_file(&staged);
        self.files.push(Planned {
            target: path.to_path_buf(),
            staged,
        });
        Ok(())
    }

    /// Where to write the output planned as `target` (`target` itself if it was not planned).
    pub fn path<'a>(&'a self, target: &'a Path) -> &'a Path {
        self.files
            .iter()
            .find(|f| f.target == target)
            .map_or(target, |f| f.staged.as_path())
    }

    /// Moves every written file into place; a planned file that was not written (an optional
    /// output the command had nothing for) leaves its target as it was.
    pub fn commit(mut self) -> Result<()> {
        for f in &self.files {
            if f.staged.exists() {
                std::fs::rename(&f.staged, &f.target)
                    .map_err(|e| Error::file("move into place", &f.target, e))?;
            }
        }
        self.committed = true;
        Ok(())
    }
}

impl Drop for StagedFiles {
    fn drop(&mut self) {
        if self.committed {
            return;
        }
        for f in &self.files {
            let _ = std::fs::remove_file(&f.staged);
        }
        for c in &self.created {
            let _ = std::fs::remove_dir_all(c);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tmp(name: &str) -> PathBuf {
        let d =
            std::env::temp_dir().join(format!("gearbif-outfiles-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn the_plan_is_refused_before_the_work() {
        let root = tmp("plan");
        let (a, b) = (root.join("a.json"), root.join("sub/../a.json"));
        std::fs::create_dir_all(root.join("sub")).unwrap();
        let e = StagedFiles::begin(&[
            ("--out", &a, FileKind::Data),
            ("--plot", &b, FileKind::Data),
        ])
        .unwrap_err();
        assert!(e.to_string().contains("both name the file"), "{e}");
        let e = StagedFiles::begin(&[("--out", &root.join("sub"), FileKind::Data)]).unwrap_err();
        assert!(e.to_string().contains("is a folder"), "{e}");
        let e =
            StagedFiles::begin(&[("--plot", &root.join("p.pdf"), FileKind::Figure)]).unwrap_err();
        assert!(e.to_string().contains(".svg or .png"), "{e}");
        std::fs::write(root.join("file"), "").unwrap();
        let e =
            StagedFiles::begin(&[("--out", &root.join("file/x.csv"), FileKind::Data)]).unwrap_err();
        assert!(e.to_string().contains("not a folder"), "{e}");
        std::fs::remove_dir_all(root).ok();
    }

    #[test]
    fn files_reach_their_targets_together_or_not_at_all() {
        let root = tmp("commit");
        let (a, b) = (root.join("new/a.csv"), root.join("b.svg"));
        std::fs::write(&b, "old").unwrap();
        let plan = [
            ("--out", a.as_path(), FileKind::Data),
            ("--plot", b.as_path(), FileKind::Figure),
        ];
        {
            let s = StagedFiles::begin(&plan).unwrap();
            std::fs::write(s.path(&a), "new").unwrap();
            // dropped before the second file: a failed run
        }
        assert!(!root.join("new").exists());
        assert_eq!(std::fs::read_to_string(&b).unwrap(), "old");
        let s = StagedFiles::begin(&plan).unwrap();
        std::fs::write(s.path(&a), "new").unwrap();
        std::fs::write(s.path(&b), "new").unwrap();
        assert_eq!(std::fs::read_to_string(&b).unwrap(), "old");
        s.commit().unwrap();
        assert_eq!(std::fs::read_to_string(&a).unwrap(), "new");
        assert_eq!(std::fs::read_to_string(&b).unwrap(), "new");
        let names: Vec<_> = std::fs::read_dir(&root)
            .unwrap()
            .flatten()
            .map(|e| e.file_name())
            .collect();
        assert_eq!(names.len(), 2, "{names:?}");
        std::fs::remove_dir_all(root).ok();
    }
}
