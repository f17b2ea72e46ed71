//! Sharded sweeps: N shards (each resumable) merged give exactly the single run, bit for bit; the
//! merge refuses shards of another spec, missing, duplicated or incomplete shards.

use gearbif::sweep::{
    merge_shards, Axis, Protocol, Shard, SweepOutcome, SweepParam, SweepRunner, SweepSpec,
};
use std::path::PathBuf;

fn spec() -> SweepSpec {
    let mut s = SweepSpec::paper_fig7(
        Axis::range(SweepParam::ThetaDeg, 0.0, 40.0, 10.0).unwrap(),
        Axis::range(SweepParam::F, 1.0, 2.0, 0.5).unwrap(),
    );
    s.protocol = Protocol::SemiStatic;
    s.classify.settle_turns = 10;
    s.classify.analysis_turns = 6;
    s
}

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("gearbif-shards-{}-{name}", std::process::id()));
    std::fs::remove_dir_all(&d).ok();
    d
}

#[test]
fn merged_shards_equal_the_single_run_bit_for_bit() {
    let spec = spec();
    let single = match SweepRunner::new(spec.clone()).run().unwrap() {
        SweepOutcome::Complete(r) => r,
        o => panic!("{o:?}"),
    };
    let n = 3;
    let dirs: Vec<PathBuf> = (0..n).map(|i| dir(&format!("s{i}"))).collect();
    for (i, d) in dirs.iter().enumerate() {
        let shard = Shard::new(i, n).unwrap();
        if i == 1 {
            // shard 1 is "killed" after one of its two rows: merging now is refused
            let st = SweepRunner::new(spec.clone())
                .checkpoint(d)
                .max_new_rows(1)
                .run_shard(shard)
                .unwrap();
            assert_eq!((st.rows_done, st.rows_total), (1, 2));
            assert!(!st.complete());
        }
        let st = SweepRunner::new(spec.clone())
            .checkpoint(d)
            .run_shard(shard)
            .unwrap();
        assert!(st.complete(), "{st:?}");
    }
    let merged = merge_shards(&dirs).unwrap();
    // bit for bit: the JSON texts (floats printed to round-trip) are identical
    assert_eq!(
        serde_json::to_string(&merged).unwrap(),
        serde_json::to_string(&single).unwrap()
    );
    assert_eq!(merged.to_csv().unwrap(), single.to_csv().unwrap());

    // a missing shard, a duplicated one
    let err = merge_shards(&dirs[..2]).unwrap_err().to_string();
    assert!(err.contains("missing: 2/3"), "{err}");
    let dup = [dirs[0].clone(), dirs[0].clone(), dirs[2].clone()];
    assert!(merge_shards(&dup)
        .unwrap_err()
        .to_string()
        .contains("twice"));

    // an incomplete shard
    let partial = dir("partial");
    SweepRunner::new(spec.clone())
        .checkpoint(&partial)
        .max_new_rows(1)
        .run_shard(Shard::new(1, n).unwrap())
        .unwrap();
    let err = merge_shards(&[dirs[0].clone(), partial.clone(), dirs[2].clone()])
        .unwrap_err()
        .to_string();
    assert!(err.contains("incomplete"), "{err}");

    // a shard of another spec, and a checkpoint reused for another shard
    let mut other_spec = spec.clone();
    other_spec.classify.settle_turns = 11;
    let other = dir("other");
    SweepRunner::new(other_spec)
        .checkpoint(&other)
        .run_shard(Shard::new(2, n).unwrap())
        .unwrap();
    let err = merge_shards(&[dirs[0].clone(), dirs[1].clone(), other.clone()])
        .unwrap_err()
        .to_string();
    assert!(err.contains("different sweeps"), "{err}");
    assert!(SweepRunner::new(spec.clone())
        .checkpoint(&dirs[0])
        .run_shard(Shard::new(1, n).unwrap())
        .is_err());
    for d in dirs.iter().chain([&partial, &other]) {
        std::fs::remove_dir_all(d).ok();
    }
}

#[test]
fn shard_partition_is_deterministic_and_checked() {
    let s = Shard::parse("2/4").unwrap();
    assert_eq!(s.rows(10).collect::<Vec<_>>(), vec![2, 6]);
    for bad in ["4/4", "1", "a/2", "1/0", "-1/3"] {
        assert!(Shard::parse(bad).is_err(), "{bad}");
    }
    // every row in exactly one shard
    let n = 7;
    let mut owners = [0; 37];
    for i in 0..n {
        for r in Shard::new(i, n).unwrap().rows(37) {
            owners[r] += 1;
        }
    }
    assert!(owners.iter().all(|&c| c == 1));
    // more shards than rows: an empty shard is refused
    let spec = spec();
    let d = dir("empty");
    assert!(SweepRunner::new(spec)
        .checkpoint(&d)
        .run_shard(Shard::new(6, 8).unwrap())
        .is_err());
    std::fs::remove_dir_all(&d).ok();
}
