//! Sweeps split into shards for a cluster scheduler: shard i of N computes the rows r with
//! r mod N = i (a deterministic partition; rows are the unit because the semi-static protocol is
//! sequential along a row). Each shard checkpoints into its own directory, with the spec and a
//! manifest naming the shard and the spec's hash, and resumes like an unsharded sweep. Since a row
//! depends only on the spec, the merged shards equal the single run bit for bit.

use super::{RowResult, SweepResult, SweepRunner, SweepSpec};
use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Shard `index` of `count` (0 ≤ index < count): the rows r with r mod count = index.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    /// This shard, 0-based.
    pub index: usize,
    /// Number of shards.
    pub count: usize,
}

impl Shard {
    /// Shard `index` of `count`; an error unless 0 ≤ index < count.
    pub fn new(index: usize, count: usize) -> Result<Self> {
        if count == 0 || index >= count {
            return Err(Error::option(
                format!("shard {index}/{count}"),
                "need 0 <= index < count",
            ));
        }
        Ok(Self { index, count })
    }

    /// Parses `i/N` (e.g. `3/8`; i is 0-based, as SLURM_ARRAY_TASK_ID with `--array=0-7`).
    pub fn parse(s: &str) -> Result<Self> {
        let bad = || Error::option(format!("--shard `{s}`"), "expected i/N with 0 <= i < N");
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let i: usize = i.trim().parse().map_err(|_| bad())?;
        let n: usize = n.trim().parse().map_err(|_| bad())?;
        Self::new(i, n)
    }

    /// Whether row `row` belongs to this shard.
    pub fn contains(&self, row: usize) -> bool {
        row % self.count == self.index
    }

    /// The rows of this shard among `nrows`.
    pub fn rows(&self, nrows: usize) -> impl Iterator<Item = usize> + '_ {
        (self.index..nrows).step_by(self.count)
    }

    /// An error if the shard would hold no row of a sweep with `nrows` rows.
    pub(super) fn check_rows(&self, nrows: usize) -> Result<()> {
        if self.index >= nrows {
            return Err(Error::inconsistent(
                "--shard, rows",
                format!(
                    "shard {}/{} is empty: the sweep has only {nrows} rows (use at most {nrows} \
                     shards)",
                    self.index, self.count
                ),
            ));
        }
        Ok(())
    }
}

/// The progress of one shard.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ShardStatus {
    /// The shard.
    pub shard: Shard,
    /// Its finished rows (loaded or computed).
    pub rows_done: usize,
    /// Its rows.
    pub rows_total: usize,
}

impl ShardStatus {
    /// All rows of the shard are done.
    pub fn complete(&self) -> bool {
        self.rows_done == self.rows_total
    }
}

/// 64-bit FNV-1a hash of the spec's JSON text (serde_json prints floats so that they round-trip,
/// so equal specs give equal text), as 16 hex digits.
pub fn spec_hash(spec: &SweepSpec) -> Result<String> {
    let text = serde_json::to_string(spec).map_err(|e| Error::format("JSON", "sweep spec", e))?;
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in text.bytes() {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    Ok(format!("{h:016x}"))
}

/// `shard.json` in a shard's checkpoint directory.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
struct Manifest {
    shard: Shard,
    spec_hash: String,
}

const MANIFEST: &str = "shard.json";

fn read_json<T: for<'de> Deserialize<'de>>(path: &Path) -> Result<T> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::file("read", path, e))?;
    serde_json::from_str(&text).map_err(|e| Error::format("JSON", path.display().to_string(), e))
}

/// Writes the manifest of a new shard checkpoint, or checks that an existing one names the same
/// shard of the same spec.
pub(super) fn check_or_write_manifest(dir: &Path, spec: &SweepSpec, shard: Shard) -> Result<()> {
    let want = Manifest {
        shard,
        spec_hash: spec_hash(spec)?,
    };
    let path = dir.join(MANIFEST);
    if path.exists() {
        let have: Manifest = read_json(&path)?;
        if have != want {
            return Err(Error::checkpoint(
                dir,
                format!(
                "the checkpoint holds shard {}/{} of spec {}, not shard {}/{} of spec {}; use another directory",
                have.shard.index,
                have.shard.count,
                have.spec_hash,
                shard.index,
                shard.count,
                want.spec_hash
            ),
            ));
        }
        return Ok(());
    }
    crate::io::write_json_atomic(&path, &want)
}

/// One shard read back from its checkpoint directory.
struct ShardData {
    dir: PathBuf,
    spec: SweepSpec,
    manifest: Manifest,
}

fn read_shard(dir: &Path) -> Result<ShardData> {
    let spec_path = dir.join("spec.json");
    let man_path = dir.join(MANIFEST);
    if !man_path.exists() {
        return Err(Error::checkpoint(
            dir,
            format!("not a shard checkpoint (no {MANIFEST}; was it run with --shard?)"),
        ));
    }
    let spec: SweepSpec = read_json(&spec_path)?;
    let manifest: Manifest = read_json(&man_path)?;
    let hash = spec_hash(&spec)?;
    if hash != manifest.spec_hash {
        return Err(Error::checkpoint(
            dir,
            format!(
                "spec.json hashes to {hash} but the manifest records {}",
                manifest.spec_hash
            ),
        ));
    }
    // a shard no run can have written (run_shard checks 0 <= i < N and i < rows)
    let Shard { index, count } = manifest.shard;
    let nrows = spec.rows.values.len();
    if count == 0 || index >= count || count > nrows {
        return Err(Error::checkpoint(
            &man_path,
            format!("shard {index}/{count} is impossible for a sweep of {nrows} rows"),
        ));
    }
    Ok(ShardData {
        dir: dir.to_path_buf(),
        spec,
        manifest,
    })
}

/// Merges the shards checkpointed in `dirs` into the result of the whole sweep. Refuses (with an
/// error naming the problem) unless all shards belong to the same spec (equal hashes) and the same
/// partition, every shard 0..N is present exactly once, and every shard is complete.
pub fn merge_shards(dirs: &[PathBuf]) -> Result<SweepResult> {
    let first = dirs
        .first()
        .ok_or_else(|| Error::shape("shard directories to merge", ">= 1", 0))?;
    let shards = dirs
        .iter()
        .map(|d| read_shard(d))
        .collect::<Result<Vec<_>>>()?;
    let base = &shards[0];
    let count = base.manifest.shard.count;
    let mut seen: Vec<Option<&Path>> = vec![None; count];
    for sd in &shards {
        if sd.manifest.spec_hash != base.manifest.spec_hash || sd.spec != base.spec {
            return Err(Error::checkpoint(
                &sd.dir,
                format!(
                    "shards belong to different sweeps: {} has spec {}, this one spec {}",
                    first.display(),
                    base.manifest.spec_hash,
                    sd.manifest.spec_hash
                ),
            ));
        }
        let sh = sd.manifest.shard;
        if sh.count != count {
            return Err(Error::checkpoint(
                &sd.dir,
                format!(
                    "shards of different partitions: this one is 1 of {}, {} is 1 of {count}",
                    sh.count,
                    first.display()
                ),
            ));
        }
        if let Some(prev) = seen[sh.index] {
            return Err(Error::checkpoint(
                &sd.dir,
                format!(
                    "shard {}/{count} given twice: {} and this one",
                    sh.index,
                    prev.display()
                ),
            ));
        }
        seen[sh.index] = Some(&sd.dir);
    }
    let missing: Vec<String> = (0..count)
        .filter(|&i| seen[i].is_none())
        .map(|i| format!("{i}/{count}"))
        .collect();
    if !missing.is_empty() {
        return Err(Error::checkpoint(
            first,
            format!("shards of this sweep missing: {}", missing.join(", ")),
        ));
    }
    let spec = base.spec.clone();
    let nrows = spec.rows.values.len();
    let ncols = spec.cols.values.len();
    let mut rows: Vec<Option<RowResult>> = vec![None; nrows];
    for sd in &shards {
        let sh = sd.manifest.shard;
        let mut absent = Vec::new();
        for i in sh.rows(nrows) {
            let p = SweepRunner::row_path(&sd.dir, i);
            if !p.exists() {
                absent.push(i);
                continue;
            }
            let r: RowResult = read_json(&p)?;
            if !spec.row_matches(i, &r) {
                return Err(Error::checkpoint(
                    &p,
                    format!("the row file does not hold row {i} of this spec with {ncols} points"),
                ));
            }
            rows[i] = Some(r);
        }
        if !absent.is_empty() {
            return Err(Error::checkpoint(
                &sd.dir,
                format!(
                "shard {}/{count} is incomplete: {} of its {} rows missing (first: row {}); rerun its command to resume",
                sh.index,
                absent.len(),
                sh.rows(nrows).count(),
                absent[0]
            ),
            ));
        }
    }
    Ok(SweepResult {
        spec,
        rows: rows.into_iter().flatten().collect(),
    })
}
