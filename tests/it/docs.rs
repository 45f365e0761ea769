//! The commands and links the documentation gives (README.md, python/README.md, the book's
//! pages under docs/src/, and the examples the book includes), checked as text:
//!
//! - every `cargo run`/`cargo test` of an example builds it with `--release` (the rest of
//!   the instructions build release: a debug build would be a second copy of everything);
//! - no link points at a placeholder host (`example.invalid`, `example.com`, ...);
//! - a page that runs a Python example (`python examples/python/...`) says how to install
//!   what it imports (`pip install "./python[examples]"`), and python/pyproject.toml has that
//!   extra with matplotlib in it.

use std::path::{Path, PathBuf};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn walk(dir: &Path, ext: &str, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            // The vendored KaTeX is not ours.
            if p.file_name().is_some_and(|n| n != "vendor") {
                walk(&p, ext, out);
            }
        } else if p.extension().is_some_and(|x| x == ext) {
            out.push(p);
        }
    }
}

/// The documentation's files: Markdown, and the examples the book includes.
fn doc_files() -> Vec<PathBuf> {
    let r = root();
    let mut files = vec![r.join("README.md"), r.join("python/README.md")];
    walk(&r.join("docs/src"), "md", &mut files);
    walk(&r.join("examples"), "rs", &mut files);
    walk(&r.join("examples/python"), "py", &mut files);
    files.sort();
    files.dedup();
    assert!(files.len() > 20, "{files:?}");
    files
}

fn lines() -> Vec<(String, usize, String)> {
    let mut out = Vec::new();
    for f in doc_files() {
        let text = std::fs::read_to_string(&f).unwrap();
        let name = f.strip_prefix(root()).unwrap().display().to_string();
        for (i, l) in text.lines().enumerate() {
            out.push((name.clone(), i + 1, l.to_owned()));
        }
    }
    out
}

/// The `cargo run`/`cargo test` commands of an example without `--release` that start in
/// `text` before byte `starts_before` (a command may wrap onto the next line of a comment: the
/// caller passes the two lines joined, and `starts_before` the first one's length).
fn example_commands_without_release(text: &str, starts_before: usize) -> Vec<String> {
    let mut bad = Vec::new();
    for (i, _) in text.match_indices("cargo ") {
        if i >= starts_before {
            break;
        }
        let cmd: String = text[i..]
            .split(['`', '#', ')', ';'])
            .next()
            .unwrap()
            .split_whitespace()
            .collect::<Vec<_>>()
            .join(" ");
        let words: Vec<&str> = cmd.split(' ').collect();
        if words.len() > 1
            && matches!(words[1], "run" | "test")
            && words.contains(&"--example")
            && !words.contains(&"--release")
        {
            bad.push(cmd);
        }
    }
    bad
}

#[test]
fn example_commands_build_release() {
    let lines = lines();
    let mut bad = Vec::new();
    for (k, (file, n, l)) in lines.iter().enumerate() {
        let joined = match lines.get(k + 1) {
            Some((next_file, _, next)) if next_file == file => {
                format!("{l} {}", next.trim_start_matches(['/', '!', '#', ' ']))
            }
            _ => l.clone(),
        };
        for cmd in example_commands_without_release(&joined, l.len()) {
            bad.push(format!("{file}:{n}: `{cmd}`"));
        }
    }
    assert!(
        bad.is_empty(),
        "example commands without --release:\n{}",
        bad.join("\n")
    );
}

#[test]
fn the_release_check_sees_a_debug_command() {
    assert_eq!(
        example_commands_without_release("run `cargo run -p satsim --example custom_effect`", 99),
        ["cargo run -p satsim --example custom_effect"]
    );
    assert_eq!(
        example_commands_without_release("`cargo test --example custom_effect`", 99),
        ["cargo test --example custom_effect"]
    );
    assert!(
        example_commands_without_release("cargo run --release -p satsim --example x # runs", 99)
            .is_empty()
    );
    assert!(example_commands_without_release("cargo build --release", 99).is_empty());
}

#[test]
fn no_placeholder_links() {
    const PLACEHOLDERS: [&str; 6] = [
        "example.invalid",
        "example.com",
        "example.org",
        "example.net",
        "github.com/user/",
        "github.com/your",
    ];
    let mut bad = Vec::new();
    for (file, n, l) in lines() {
        for p in PLACEHOLDERS {
            if l.contains(p) {
                bad.push(format!("{file}:{n}: {l}"));
            }
        }
    }
    assert!(bad.is_empty(), "placeholder links:\n{}", bad.join("\n"));
}

#[test]
fn python_examples_say_how_to_install_what_they_import() {
    let pyproject = std::fs::read_to_string(root().join("python/pyproject.toml")).unwrap();
    let t: toml::Table = pyproject.parse().unwrap();
    let examples = t["project"]["optional-dependencies"]["examples"]
        .as_array()
        .expect("python/pyproject.toml has an `examples` extra");
    for needed in ["matplotlib", "pandas", "dask", "distributed"] {
        assert!(
            examples.iter().any(|v| v.as_str() == Some(needed)),
            "the `examples` extra lacks {needed}"
        );
    }
    let mut bad = Vec::new();
    for f in doc_files() {
        let text = std::fs::read_to_string(&f).unwrap();
        if text.contains("python examples/python/")
            && !text.contains("pip install \"./python[examples]\"")
        {
            bad.push(f.strip_prefix(root()).unwrap().display().to_string());
        }
    }
    assert!(
        bad.is_empty(),
        "these run a Python example without `pip install \"./python[examples]\"`: {bad:?}"
    );
}
