//! Every image the documentation shows is made by a command the documentation lists: the table of
//! `docs/figures/README.md` maps each image to its command. Checked here by reading the files only
//! (nothing is rendered): every image referenced from README.md and docs/*.md is in the table and
//! exists; every image file under docs/figures is in the table; every command of the table writes
//! its image (the output folder or file in its arguments, the file name in the source that
//! produces it, a subcommand or example that exists).

use std::collections::BTreeMap;
use std::path::{Component, Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// `a/b/../c` → `a/c` (no file system access).
fn normalize(p: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in p.components() {
        match c {
            Component::ParentDir => {
                out.pop();
            }
            Component::CurDir => {}
            c => out.push(c),
        }
    }
    out
}

/// Image targets of `![alt](target)` in a Markdown text.
fn image_refs(md: &str) -> Vec<String> {
    let mut v = Vec::new();
    let mut rest = md;
    while let Some(i) = rest.find("![") {
        rest = &rest[i + 2..];
        let Some(close) = rest.find("](") else { break };
        let after = &rest[close + 2..];
        if let Some(end) = after.find(')') {
            v.push(after[..end].trim().to_string());
        }
        rest = after;
    }
    v
}

/// The manifest: image path (relative to the repository root) → command.
fn manifest() -> BTreeMap<PathBuf, String> {
    let text = read(&root().join("docs/figures/README.md"));
    let mut m = BTreeMap::new();
    for line in text.lines() {
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        // | `image` | `command` |
        if cells.len() == 4 && cells[1].starts_with('`') && cells[2].starts_with('`') {
            let img = cells[1].trim_matches('`');
            let cmd = cells[2].trim_matches('`');
            let prev = m.insert(
                normalize(&Path::new("docs/figures").join(img)),
                cmd.to_string(),
            );
            assert!(prev.is_none(), "{img} is listed twice");
        }
    }
    assert!(m.len() >= 20, "the manifest table was not found");
    m
}

/// The value of `--flag VALUE` in a command.
fn flag<'a>(words: &[&'a str], flag: &str) -> Option<&'a str> {
    words.iter().position(|w| *w == flag).map(|i| words[i + 1])
}

/// Checks that `cmd` writes `img` (relative to the root); returns an error text otherwise.
fn check_command(img: &Path, cmd: &str) -> Result<(), String> {
    let words: Vec<&str> = cmd.split_whitespace().collect();
    let stem = img.file_stem().and_then(|s| s.to_str()).unwrap_or("");
    let dir = img.parent().unwrap_or(Path::new(""));
    let src_has = |file: &str, what: &str| -> Result<(), String> {
        if read(&root().join(file)).contains(&format!("\"{what}")) {
            Ok(())
        } else {
            Err(format!("{file} does not name the output {what}"))
        }
    };
    match words.as_slice() {
        ["cargo", "run", "--release", "--", sub, rest @ ..] => {
            let cli = format!("src/cli/{}.rs", sub.replace('-', "_"));
            // `continue` is a keyword: its module is continue_.rs
            let cli_ = format!("src/cli/{}_.rs", sub.replace('-', "_"));
            let cli = if root().join(&cli).is_file() {
                cli
            } else if root().join(&cli_).is_file() {
                cli_
            } else if *sub == "bench-integrators" {
                "src/cli/bench.rs".to_string()
            } else {
                return Err(format!("no subcommand {sub}"));
            };
            if *sub == "figure" {
                let name = rest.first().ok_or("figure needs a name")?;
                let variant: String = name[..1].to_uppercase() + &name[1..];
                if !read(&root().join(&cli)).contains(&format!("    {variant},")) {
                    return Err(format!("no figure {name}"));
                }
                // the figure's files are named after it: fig9 → fig9-avg, fig10 → fig10a
                let named = stem
                    .strip_prefix(*name)
                    .is_some_and(|r| !r.starts_with(|c: char| c.is_ascii_digit()));
                if !named {
                    return Err(format!("figure {name} does not make {stem}"));
                }
                let out = flag(&words, "--out").ok_or("figure needs --out")?;
                if Path::new(out) != dir {
                    return Err(format!("figure writes into {out}, not {}", dir.display()));
                }
                return src_has(&cli, stem);
            }
            if let (None, None, Some(out)) = (
                flag(&words, "--plot"),
                flag(&words, "--figure"),
                flag(&words, "--out"),
            ) {
                // a command writing a folder: the image's folder, the name in its source
                if Path::new(out) != dir {
                    return Err(format!("{sub} writes into {out}"));
                }
                return src_has(&cli, stem);
            }
            let target = flag(&words, "--plot")
                .or_else(|| flag(&words, "--figure"))
                .ok_or("no --plot, --figure or --out output")?;
            if Path::new(target) == img {
                Ok(())
            } else {
                Err(format!("{sub} writes {target}"))
            }
        }
        ["cargo", "run", "--release", "--example", name, out, ..] => {
            let file = format!("examples/{name}.rs");
            if !root().join(&file).is_file() {
                return Err(format!("no example {name}"));
            }
            if Path::new(out) != dir {
                return Err(format!("the example writes into {out}"));
            }
            src_has(&file, stem)
        }
        ["python", script, "--out", out, ..] => {
            if !root().join(script).is_file() {
                return Err(format!("no script {script}"));
            }
            if Path::new(out) == img {
                Ok(())
            } else {
                Err(format!("the script writes {out}"))
            }
        }
        _ => Err("not a `cargo run --release` or `python` command".into()),
    }
}

#[test]
fn every_documented_image_has_a_listed_command_that_makes_it() {
    let m = manifest();
    let mut docs: Vec<PathBuf> = vec![PathBuf::from("README.md")];
    for e in std::fs::read_dir(root().join("docs")).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "md") {
            docs.push(p.strip_prefix(root()).unwrap().to_path_buf());
        }
    }
    let mut problems = Vec::new();
    let mut referenced = 0;
    for d in &docs {
        for target in image_refs(&read(&root().join(d))) {
            if target.contains("://") {
                continue;
            }
            referenced += 1;
            let img = normalize(&d.parent().unwrap_or(Path::new("")).join(&target));
            if !root().join(&img).is_file() {
                problems.push(format!("{}: {} does not exist", d.display(), img.display()));
            }
            if !m.contains_key(&img) {
                problems.push(format!(
                    "{}: {} has no command in docs/figures/README.md",
                    d.display(),
                    img.display()
                ));
            }
        }
    }
    assert!(
        referenced >= 20,
        "only {referenced} images found in the docs"
    );
    for (img, cmd) in &m {
        if !root().join(img).is_file() {
            problems.push(format!("listed {} does not exist", img.display()));
        }
        if let Err(e) = check_command(img, cmd) {
            problems.push(format!("{}: `{cmd}`: {e}", img.display()));
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

#[test]
fn every_image_file_under_docs_figures_is_listed() {
    let m = manifest();
    let mut stack = vec![root().join("docs/figures")];
    let mut unlisted = Vec::new();
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if p
                .extension()
                .is_some_and(|x| x == "png" || x == "svg" || x == "jpg")
            {
                let rel = p.strip_prefix(root()).unwrap().to_path_buf();
                if !m.contains_key(&rel) {
                    unlisted.push(rel.display().to_string());
                }
            }
        }
    }
    assert!(
        unlisted.is_empty(),
        "images without a command: {unlisted:?}"
    );
}

#[test]
fn the_checks_catch_wrong_commands() {
    let img = Path::new("docs/figures/fig9-avg.png");
    assert!(check_command(img, "cargo run --release -- figure fig9 --out docs/figures").is_ok());
    // wrong figure, wrong folder, unknown figure, a file name the command does not write
    assert!(check_command(img, "cargo run --release -- figure fig5 --out docs/figures").is_err());
    assert!(check_command(img, "cargo run --release -- figure fig9 --out figs").is_err());
    assert!(check_command(
        img,
        "cargo run --release -- figure fig99 --out docs/figures"
    )
    .is_err());
    let other = Path::new("docs/figures/fig9-nothing.png");
    assert!(check_command(
        other,
        "cargo run --release -- figure fig9 --out docs/figures"
    )
    .is_err());
    assert!(check_command(img, "python make.py").is_err());
    assert!(check_command(img, "python docs/none.py --out docs/figures/fig9-avg.png").is_err());
    assert_eq!(
        image_refs("a ![x](figures/a.png) b ![](../c.svg)"),
        ["figures/a.png", "../c.svg"]
    );
}
