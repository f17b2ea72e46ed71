//! Executed docs: the command-line blocks of docs/tutorial.md marked `<!-- check: … quick -->` are
//! run by scripts/check_tutorial.py with this build's binary, and what they print must agree with
//! the page (words exactly, numbers within each block's stated tolerance). A stale block fails.
//! The diagnosis of §4 is among them (about 13 s in the test build); the Python blocks are checked
//! by python/tests/test_tutorial.py.

use std::path::Path;
use std::process::Command;

fn check(page: &Path) -> (bool, String) {
    let root = env!("CARGO_MANIFEST_DIR");
    let out = Command::new("python3")
        .arg(Path::new(root).join("scripts/check_tutorial.py"))
        .args(["--bin", env!("CARGO_BIN_EXE_gearbif"), "--quick", "--page"])
        .arg(page)
        .output()
        .expect("python3 runs scripts/check_tutorial.py");
    let text =
        String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr);
    (out.status.success(), text)
}

#[test]
fn the_tutorials_quick_command_blocks_print_what_the_page_shows() {
    let page = Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/tutorial.md");
    let (ok, text) = check(&page);
    assert!(ok, "docs/tutorial.md is stale:\n{text}");
    assert!(text.contains("checked blocks agree"), "{text}");
}

#[test]
fn a_number_changed_on_the_page_fails_the_check() {
    let page = Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/tutorial.md");
    let good = std::fs::read_to_string(&page).unwrap();
    // the located flip of the continuation block, moved by 5e-8 relative (the block's tolerance is 1e-9)
    let line = "[3] flip               f = 1.854934870";
    assert!(
        good.contains(line),
        "the tutorial's continuation block has moved: update this test"
    );
    let bad = good.replacen(line, "[3] flip               f = 1.854934970", 1);
    // the page up to the diagnosis (§4): the slowest quick block runs once, in the test above
    let bad = &bad[..bad.find("## 4. ").expect("the tutorial's §4")];
    let dir = std::env::temp_dir().join(format!("gearbif-tutorial-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let copy = dir.join("tutorial.md");
    std::fs::write(&copy, bad).unwrap();
    let (ok, text) = check(&copy);
    std::fs::remove_dir_all(&dir).ok();
    assert!(!ok, "a changed number passed the check:\n{text}");
    assert!(text.contains("page 1.85493497"), "{text}");
}
