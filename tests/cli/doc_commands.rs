//! Every shell command shown in a ```sh block of README.md and docs/*.md runs as printed and
//! exits 0: each `goniofit …` line (continuation lines joined, a trailing `# comment`
//! dropped) runs with the built binary in a fresh folder that sees the repository's `data/`.
//! The README's two set-up commands (`cargo run …` builds and runs the first fit, `bash
//! tests/all.sh` runs every test) are what CI itself runs, so they are only recognised here;
//! any other command in such a block fails the test until it is recognised.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The commands of the ```sh blocks of `text` (continuations joined, comments dropped).
fn sh_commands(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut in_block = false;
    let mut pending = String::new();
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            in_block = !in_block && line.trim() == "```sh";
            continue;
        }
        if !in_block {
            continue;
        }
        let code = line.split(" #").next().unwrap_or("").trim_end();
        match code.strip_suffix('\\') {
            Some(head) => pending.push_str(head),
            None => {
                pending.push_str(code);
                let command = pending.split_whitespace().collect::<Vec<_>>().join(" ");
                if !command.is_empty() {
                    out.push(command);
                }
                pending.clear();
            }
        }
    }
    out
}

/// The documents whose commands are run: README.md and every docs/*.md.
fn documents(repo: &Path) -> Vec<PathBuf> {
    let mut docs: Vec<PathBuf> = std::fs::read_dir(repo.join("docs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    docs.sort();
    docs.insert(0, repo.join("README.md"));
    docs
}

#[test]
fn every_shell_command_in_readme_and_docs_runs() {
    let repo = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = tempfile::tempdir().unwrap();
    std::os::unix::fs::symlink(repo.join("data"), dir.path().join("data")).unwrap();
    let mut ran = 0;
    let mut failures = Vec::new();
    for doc in documents(repo) {
        let text = std::fs::read_to_string(&doc).unwrap();
        for command in sh_commands(&text) {
            let name = doc.file_name().unwrap().to_string_lossy().to_string();
            if command.starts_with("cargo run --release -- fit ") || command == "bash tests/all.sh"
            {
                continue;
            }
            let Some(args) = command.strip_prefix("goniofit ") else {
                failures.push(format!("{name}: `{command}` is not a goniofit command"));
                continue;
            };
            let out = Command::new(env!("CARGO_BIN_EXE_goniofit"))
                .args(args.split_whitespace())
                .current_dir(dir.path())
                .output()
                .unwrap();
            ran += 1;
            if !out.status.success() {
                failures.push(format!(
                    "{name}: `{command}` exited {:?}: {}",
                    out.status.code(),
                    String::from_utf8_lossy(&out.stderr)
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
    assert!(
        ran >= 4,
        "only {ran} commands found in the documents' sh blocks"
    );
}

#[test]
fn commands_are_read_from_sh_blocks_with_continuations_and_comments() {
    let text =
        "text\n```sh\ngoniofit a \\\n    b  # note\n\ngoniofit c\n```\n```text\ngoniofit d\n```\n";
    assert_eq!(sh_commands(text), vec!["goniofit a b", "goniofit c"]);
}
