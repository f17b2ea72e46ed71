//! The output folder of a resumable job (`sweep`, `campaign`): the folder is the work, written as
//! the job goes (checkpoint rows, finished cases, each file atomically) so that a rerun resumes
//! from it; the result files are written when the work is complete, and the completion marker
//! `complete.json` last. [`WorkDir::begin`] removes the marker before anything else is written,
//! so a folder with the marker holds one whole result and a folder without it is work in
//! progress (killed, failed or stopped), whatever result files it holds.
//!
//! The plan is checked before the work: the target is a folder or absent, no name of the result
//! exists with the wrong kind (a folder `points.csv`), and a file can be created in it (a
//! read-only mount is found here, not after the work). Names that are not the job's are left
//! alone.

use crate::error::{Error, Result};
use std::path::{Path, PathBuf};

/// The name of the completion marker.
pub const MARKER: &str = "complete.json";

/// The marker's content: what the folder holds when complete.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Complete {
    /// The schema id, `gearbif.complete/1`.
    pub schema: String,
    /// The command that wrote the folder (`sweep`, `campaign`).
    pub command: String,
    /// The result files, relative to the folder.
    pub files: Vec<String>,
}

/// A resumable job's output folder (see the module documentation).
#[derive(Debug)]
pub struct WorkDir {
    target: PathBuf,
    command: &'static str,
    /// The first folder of the target's path this run created: removed again, if still empty,
    /// when the run ends without writing anything (an error found after the plan check).
    created: Option<PathBuf>,
}

impl WorkDir {
    /// Checks the plan of the job `command` writing the folder `target` (given by `flag`), whose
    /// result names are `files` and `dirs`, creates the folder and removes its marker.
    pub fn begin(
        flag: &str,
        target: &Path,
        command: &'static str,
        files: &[&str],
        dirs: &[&str],
    ) -> Result<Self> {
        let what = || format!("{flag} {}", target.display());
        crate::io::outdir::check_ancestors(flag, target)?;
        let planned = files
            .iter()
            .chain([MARKER].iter())
            .map(|n| (n, false))
            .chain(dirs.iter().map(|n| (n, true)));
        {
            for (n, want_dir) in planned {
                let p = target.join(n);
                if p.exists() && p.is_dir() != want_dir {
                    let (is, meant) = if want_dir {
                        ("file", "folder")
                    } else {
                        ("folder", "file")
                    };
                    return Err(Error::option(
                        what(),
                        format!("holds the {is} `{n}` where the result has a {meant}"),
                    ));
                }
            }
        }
        let created = crate::io::outdir::create_missing(target)?;
        let probe = target.join(format!(".probe.tmp-{}", std::process::id()));
        std::fs::write(&probe, b"").map_err(|e| Error::file("write", &probe, e))?;
        let _ = std::fs::remove_file(&probe);
        let marker = target.join(MARKER);
        if marker.exists() {
            std::fs::remove_file(&marker).map_err(|e| Error::file("remove", &marker, e))?;
        }
        Ok(Self {
            target: target.to_path_buf(),
            command,
            created,
        })
    }

    /// The folder.
    pub fn path(&self) -> &Path {
        &self.target
    }

    /// Writes the marker, naming the result files `files` (written before this call).
    pub fn complete(mut self, files: &[&str]) -> Result<()> {
        self.created = None;
        let c = Complete {
            schema: "gearbif.complete/1".into(),
            command: self.command.into(),
            files: files.iter().map(|f| f.to_string()).collect(),
        };
        crate::io::write_json_atomic(self.target.join(MARKER), &c)
    }
}

impl Drop for WorkDir {
    fn drop(&mut self) {
        let Some(first) = &self.created else { return };
        let mut d = Some(self.target.as_path());
        while let Some(p) = d {
            if std::fs::remove_dir(p).is_err() || p == first.as_path() {
                break;
            }
            d = p.parent();
        }
    }
}

/// True if `dir` holds a completion marker that parses and names only files that exist.
pub fn is_complete(dir: &Path) -> bool {
    std::fs::read_to_string(dir.join(MARKER))
        .ok()
        .and_then(|t| serde_json::from_str::<Complete>(&t).ok())
        .is_some_and(|c| c.files.iter().all(|f| dir.join(f).is_file()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_marker_is_removed_at_the_start_and_written_last() {
        let root = std::env::temp_dir().join(format!("gearbif-workdir-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        let out = root.join("out");
        let w = WorkDir::begin("--out", &out, "sweep", &["points.csv"], &["checkpoint"]).unwrap();
        std::fs::write(out.join("points.csv"), "x").unwrap();
        assert!(!is_complete(&out));
        w.complete(&["points.csv"]).unwrap();
        assert!(is_complete(&out));
        // a rerun: incomplete from its start on, whatever result files the folder holds
        let w = WorkDir::begin("--out", &out, "sweep", &["points.csv"], &["checkpoint"]).unwrap();
        assert!(!is_complete(&out) && out.join("points.csv").exists());
        drop(w);
        // a name of the result with the wrong kind is refused before anything is written
        std::fs::remove_file(out.join("points.csv")).unwrap();
        std::fs::create_dir(out.join("points.csv")).unwrap();
        std::fs::write(out.join("checkpoint"), "").unwrap();
        let e = WorkDir::begin("--out", &out, "sweep", &["x"], &["checkpoint"]).unwrap_err();
        assert!(e.to_string().contains("file `checkpoint`"), "{e}");
        let e = WorkDir::begin("--out", &out, "sweep", &["points.csv"], &[]).unwrap_err();
        assert!(e.to_string().contains("folder `points.csv`"), "{e}");
        // a run that ends before writing anything leaves no folder it created
        drop(WorkDir::begin("--out", &root.join("a/b"), "sweep", &[], &[]).unwrap());
        assert!(!root.join("a").exists());
        std::fs::remove_dir_all(root).ok();
    }
}
