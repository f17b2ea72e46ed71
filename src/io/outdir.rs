//! One way to write an output folder as one result: the plan is checked before the work (the
//! target is a folder or absent, it holds nothing but the names of the command's result, each of
//! the right kind, and its parent is writable: a staging folder is created there at once); the
//! work writes into the staging folder `.NAME.tmp-PID` beside the target; [`StagedDir::commit`]
//! moves it into place (an earlier result is first moved aside to `.NAME.old-PID`, then removed).
//! A run that fails removes its staging folder (and the folders it created); a killed one leaves
//! only hidden temporaries, which the next run beside the same target removes. So the target
//! always holds one whole result, the earlier one or the new one, never a mix.

use crate::error::{Error, Result};
use std::path::{Path, PathBuf};

/// What a command's result consists of: `true` for a name (directly under the folder) that belongs
/// to it, with whether that name is a folder.
pub type Owned = fn(name: &str, is_dir: bool) -> bool;

/// An output folder being written (see the module documentation).
#[derive(Debug)]
pub struct StagedDir {
    target: PathBuf,
    staging: PathBuf,
    /// The first ancestor of the target this run created (removed again on failure).
    created: Option<PathBuf>,
    mode: Mode,
    committed: bool,
}

/// How a staged result reaches its target.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Mode {
    /// The result is the whole folder: staged beside it, it replaces the folder.
    Replace,
    /// The result is some of the folder's names (one figure among others): staged in a hidden
    /// folder inside it, each name replaces its namesake and the others stay.
    Merge,
}

/// `.NAME.tmp-PID` / `.NAME.old-PID` beside `target`.
fn sibling(target: &Path, kind: &str, pid: u32) -> Result<PathBuf> {
    let name = target.file_name().ok_or_else(|| {
        Error::option(
            format!("output folder {}", target.display()),
            "is not a folder name (it ends in `..` or is a root)",
        )
    })?;
    Ok(parent_of(target).join(format!(".{}.{kind}-{pid}", name.to_string_lossy())))
}

fn parent_of(target: &Path) -> &Path {
    target
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."))
}

/// True if process `pid` is gone (Linux); elsewhere nothing is taken as gone.
fn gone(pid: u32) -> bool {
    cfg!(target_os = "linux")
        && pid != std::process::id()
        && !Path::new("/proc").join(pid.to_string()).exists()
}

/// Removes the staging and set-aside folders of killed runs beside `target`; if the target is
/// missing and a killed run had set an earlier result aside, that result is put back.
fn clean_killed(target: &Path) {
    let (Some(name), Ok(entries)) = (
        target.file_name().map(|n| n.to_string_lossy().to_string()),
        std::fs::read_dir(parent_of(target)),
    ) else {
        return;
    };
    for e in entries.flatten() {
        let entry = e.file_name().to_string_lossy().to_string();
        let Some(rest) = entry
            .strip_prefix('.')
            .and_then(|r| r.strip_prefix(name.as_str()))
        else {
            continue;
        };
        let (kind, pid) = match rest.split_once('-') {
            Some((".tmp", pid)) => ("tmp", pid),
            Some((".old", pid)) => ("old", pid),
            _ => continue,
        };
        let Ok(pid) = pid.parse::<u32>() else {
            continue;
        };
        if !gone(pid) {
            continue;
        }
        if kind == "old" && !target.exists() && std::fs::rename(e.path(), target).is_ok() {
            continue;
        }
        let _ = std::fs::remove_dir_all(e.path());
    }
}

impl StagedDir {
    /// Checks the plan of writing the folder `target` (given by `flag`) and creates its staging
    /// folder. Refused: a target that is not a folder, the current folder, a folder holding a
    /// name that is not part of the result (`owned`) or one of the wrong kind (a folder where a
    /// file is meant), and a parent that cannot be written.
    pub fn begin(flag: &str, target: &Path, owned: Owned) -> Result<Self> {
        let what = || format!("{flag} {}", target.display());
        check_ancestors(flag, target)?;
        if target.exists() {
            let cwd = std::env::current_dir().ok();
            let real = target.canonicalize().ok();
            if real.is_some() && real == cwd.and_then(|c| c.canonicalize().ok()) {
                return Err(Error::option(
                    what(),
                    "is the current folder: the result replaces its folder as a whole, give a \
                     new or result folder",
                ));
            }
            let entries = std::fs::read_dir(target).map_err(|e| Error::file("read", target, e))?;
            for e in entries.flatten() {
                let name = e.file_name().to_string_lossy().to_string();
                if name.starts_with('.') && name.contains(".tmp-") {
                    continue; // a killed atomic writer's temporary file
                }
                let is_dir = e.file_type().is_ok_and(|t| t.is_dir());
                if !owned(&name, is_dir) {
                    let kind = if is_dir { "folder" } else { "file" };
                    return Err(Error::option(
                        what(),
                        format!(
                            "holds the {kind} `{name}`, which is not part of this command's \
                             result (the folder is replaced as a whole): give a new folder or \
                             one holding an earlier result"
                        ),
                    ));
                }
            }
        }
        clean_killed(target);
        let created = create_missing(parent_of(target))?;
        let staging = fresh_staging(target, created.as_deref())?;
        Ok(Self {
            target: target.to_path_buf(),
            staging,
            created,
            mode: Mode::Replace,
            committed: false,
        })
    }

    /// Checks the plan of writing some names into the folder `target` (given by `flag`) beside
    /// what it holds, and creates the staging folder `.LABEL.tmp-PID` inside it. Refused: a
    /// target that is not a folder, and a name of the result (`owned`) that exists with the
    /// wrong kind (a folder where a file is meant); other names are left alone.
    pub fn begin_merge(flag: &str, target: &Path, label: &str, owned: Owned) -> Result<Self> {
        let what = || format!("{flag} {}", target.display());
        check_ancestors(flag, target)?;
        if target.exists() {
            let entries = std::fs::read_dir(target).map_err(|e| Error::file("read", target, e))?;
            for e in entries.flatten() {
                let name = e.file_name().to_string_lossy().to_string();
                let is_dir = e.file_type().is_ok_and(|t| t.is_dir());
                if !name.starts_with('.') && !owned(&name, is_dir) && owned(&name, !is_dir) {
                    let (is, meant) = if is_dir {
                        ("folder", "file")
                    } else {
                        ("file", "folder")
                    };
                    return Err(Error::option(
                        what(),
                        format!("holds the {is} `{name}` where the result has a {meant}"),
                    ));
                }
            }
        }
        let created = create_missing(target)?;
        clean_killed(&target.join(label));
        let staging = fresh_staging(&target.join(label), created.as_deref())?;
        Ok(Self {
            target: target.to_path_buf(),
            staging,
            created,
            mode: Mode::Merge,
            committed: false,
        })
    }

    /// The folder to write the result into.
    pub fn path(&self) -> &Path {
        &self.staging
    }

    /// The final folder.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Moves the result into place: an earlier result is replaced as a whole (or, for
    /// [`StagedDir::begin_merge`], each name of the result replaces its namesake).
    pub fn commit(mut self) -> Result<()> {
        if self.mode == Mode::Merge {
            self.merge()?;
        } else if self.target.exists() {
            let old = sibling(&self.target, "old", std::process::id())?;
            let _ = std::fs::remove_dir_all(&old);
            std::fs::rename(&self.target, &old)
                .map_err(|e| Error::file("move aside", &self.target, e))?;
            if let Err(e) = std::fs::rename(&self.staging, &self.target) {
                let _ = std::fs::rename(&old, &self.target);
                return Err(Error::file("move into place", &self.target, e));
            }
            let _ = std::fs::remove_dir_all(&old);
        } else {
            std::fs::rename(&self.staging, &self.target)
                .map_err(|e| Error::file("move into place", &self.target, e))?;
        }
        self.committed = true;
        Ok(())
    }
}

impl StagedDir {
    /// Moves each name of the staging folder over its namesake in the target (a folder is moved
    /// aside first and removed after), then removes the empty staging folder.
    fn merge(&self) -> Result<()> {
        let entries =
            std::fs::read_dir(&self.staging).map_err(|e| Error::file("read", &self.staging, e))?;
        for e in entries.flatten() {
            let to = self.target.join(e.file_name());
            if to.is_dir() {
                let old = sibling(&to, "old", std::process::id())?;
                let _ = std::fs::remove_dir_all(&old);
                std::fs::rename(&to, &old).map_err(|err| Error::file("move aside", &to, err))?;
                std::fs::rename(e.path(), &to)
                    .map_err(|err| Error::file("move into place", &to, err))?;
                let _ = std::fs::remove_dir_all(&old);
            } else {
                std::fs::rename(e.path(), &to)
                    .map_err(|err| Error::file("move into place", &to, err))?;
            }
        }
        let _ = std::fs::remove_dir(&self.staging);
        Ok(())
    }
}

/// Refuses a target under a regular file (its nearest existing ancestor must be a folder).
pub(crate) fn check_ancestors(flag: &str, target: &Path) -> Result<()> {
    let what = || format!("{flag} {}", target.display());
    if target.exists() && !target.is_dir() {
        return Err(Error::option(what(), "exists and is not a folder"));
    }
    let mut up = target.parent();
    while let Some(q) = up.filter(|q| !q.as_os_str().is_empty()) {
        if q.exists() {
            if !q.is_dir() {
                return Err(Error::option(
                    what(),
                    format!("{} is not a folder", q.display()),
                ));
            }
            break;
        }
        up = q.parent();
    }
    Ok(())
}

/// Creates `dir` and its missing ancestors; returns the first one created (to remove on failure).
pub(crate) fn create_missing(dir: &Path) -> Result<Option<PathBuf>> {
    if dir.exists() {
        return Ok(None);
    }
    let mut first = dir;
    while let Some(up) = first.parent().filter(|p| !p.as_os_str().is_empty()) {
        if up.exists() {
            break;
        }
        first = up;
    }
    std::fs::create_dir_all(dir).map_err(|e| Error::file("create", dir, e))?;
    Ok(Some(first.to_path_buf()))
}

impl Drop for StagedDir {
    fn drop(&mut self) {
        if !self.committed {
            let _ = std::fs::remove_dir_all(&self.staging);
            if let Some(c) = &self.created {
                let _ = std::fs::remove_dir_all(c);
            }
        }
    }
}

/// Creates the empty staging folder `.NAME.tmp-PID` beside `path` (an earlier one of this process
/// removed); on failure removes the folders `created` for the plan and names the staging folder.
fn fresh_staging(path: &Path, created: Option<&Path>) -> Result<PathBuf> {
    let staging = sibling(path, "tmp", std::process::id())?;
    let _ = std::fs::remove_dir_all(&staging);
    if let Err(e) = std::fs::create_dir(&staging) {
        if let Some(c) = created {
            let _ = std::fs::remove_dir_all(c);
        }
        return Err(Error::file("create", &staging, e));
    }
    Ok(staging)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tmp(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("gearbif-outdir-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    fn owned(name: &str, is_dir: bool) -> bool {
        !is_dir && matches!(name, "a.txt" | "b.txt")
    }

    fn names(d: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(d)
            .unwrap()
            .flatten()
            .map(|e| e.file_name().to_string_lossy().to_string())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn a_result_replaces_the_earlier_one_as_a_whole() {
        let root = tmp("replace");
        let out = root.join("deep/out");
        let s = StagedDir::begin("--out", &out, owned).unwrap();
        std::fs::write(s.path().join("a.txt"), "1").unwrap();
        std::fs::write(s.path().join("b.txt"), "1").unwrap();
        s.commit().unwrap();
        assert_eq!(names(&out), ["a.txt", "b.txt"]);
        let s = StagedDir::begin("--out", &out, owned).unwrap();
        std::fs::write(s.path().join("a.txt"), "2").unwrap();
        s.commit().unwrap();
        assert_eq!(names(&out), ["a.txt"]);
        assert_eq!(std::fs::read_to_string(out.join("a.txt")).unwrap(), "2");
        assert_eq!(names(&root.join("deep")), ["out"]);
        std::fs::remove_dir_all(root).ok();
    }

    #[test]
    fn a_failed_run_leaves_the_earlier_result_and_nothing_else() {
        let root = tmp("fail");
        let out = root.join("out");
        std::fs::create_dir(&out).unwrap();
        std::fs::write(out.join("a.txt"), "old").unwrap();
        {
            let s = StagedDir::begin("--out", &out, owned).unwrap();
            std::fs::write(s.path().join("a.txt"), "new").unwrap();
            // dropped without commit: the work failed
        }
        assert_eq!(names(&root), ["out"]);
        assert_eq!(std::fs::read_to_string(out.join("a.txt")).unwrap(), "old");
        // a new folder under missing parents: nothing is left of them
        {
            let _s = StagedDir::begin("--out", &root.join("x/y/out"), owned).unwrap();
        }
        assert_eq!(names(&root), ["out"]);
        std::fs::remove_dir_all(root).ok();
    }

    #[test]
    fn the_plan_is_refused_before_the_work() {
        let root = tmp("plan");
        let out = root.join("out");
        std::fs::create_dir_all(out.join("a.txt")).unwrap();
        let e = StagedDir::begin("--out", &out, owned).unwrap_err();
        assert!(e.to_string().contains("folder `a.txt`"), "{e}");
        std::fs::remove_dir_all(out.join("a.txt")).unwrap();
        std::fs::write(out.join("data.csv"), "mine").unwrap();
        let e = StagedDir::begin("--out", &out, owned).unwrap_err();
        assert!(e.to_string().contains("file `data.csv`"), "{e}");
        std::fs::write(root.join("file"), "").unwrap();
        let e = StagedDir::begin("--out", &root.join("file"), owned).unwrap_err();
        assert!(e.to_string().contains("not a folder"), "{e}");
        assert_eq!(names(&root), ["file", "out"]);
        std::fs::remove_dir_all(root).ok();
    }

    #[test]
    fn temporaries_of_killed_runs_are_removed_and_a_set_aside_result_restored() {
        let root = tmp("killed");
        let out = root.join("out");
        // a killed run: its staging folder, and an earlier result set aside with no target
        std::fs::create_dir_all(root.join(".out.tmp-999999999")).unwrap();
        std::fs::create_dir_all(root.join(".out.old-999999998")).unwrap();
        std::fs::write(root.join(".out.old-999999998/a.txt"), "old").unwrap();
        let s = StagedDir::begin("--out", &out, owned).unwrap();
        if cfg!(target_os = "linux") {
            assert_eq!(std::fs::read_to_string(out.join("a.txt")).unwrap(), "old");
            assert!(!root.join(".out.tmp-999999999").exists());
        }
        drop(s);
        std::fs::remove_dir_all(root).ok();
    }

    #[test]
    fn a_merged_result_replaces_only_its_own_names() {
        let root = tmp("merge");
        let out = root.join("figs");
        std::fs::create_dir_all(out.join("f-data")).unwrap();
        std::fs::write(out.join("f-data/old.csv"), "old").unwrap();
        std::fs::write(out.join("f.svg"), "old").unwrap();
        std::fs::write(out.join("g.svg"), "other").unwrap();
        let owned = |n: &str, d: bool| {
            if d {
                n.ends_with("-data")
            } else {
                n.ends_with(".svg")
            }
        };
        {
            let s = StagedDir::begin_merge("--out", &out, "figure-f", owned).unwrap();
            std::fs::write(s.path().join("f.svg"), "new").unwrap();
        }
        assert_eq!(names(&out), ["f-data", "f.svg", "g.svg"]);
        assert_eq!(std::fs::read_to_string(out.join("f.svg")).unwrap(), "old");
        let s = StagedDir::begin_merge("--out", &out, "figure-f", owned).unwrap();
        std::fs::write(s.path().join("f.svg"), "new").unwrap();
        std::fs::create_dir(s.path().join("f-data")).unwrap();
        std::fs::write(s.path().join("f-data/new.csv"), "new").unwrap();
        s.commit().unwrap();
        assert_eq!(names(&out), ["f-data", "f.svg", "g.svg"]);
        assert_eq!(names(&out.join("f-data")), ["new.csv"]);
        assert_eq!(std::fs::read_to_string(out.join("g.svg")).unwrap(), "other");
        std::fs::remove_file(out.join("g.svg")).unwrap();
        std::fs::create_dir(out.join("g.svg")).unwrap();
        let e = StagedDir::begin_merge("--out", &out, "figure-f", owned).unwrap_err();
        assert!(e.to_string().contains("folder `g.svg`"), "{e}");
        std::fs::remove_dir_all(root).ok();
    }
}
