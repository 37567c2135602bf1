//! The `qcs` binary as a shell user meets it: exit codes, and a reader that stops early.
#![cfg(feature = "cli")]

use std::io::{BufRead, BufReader};
use std::path::PathBuf;
use std::process::{Command, Output, Stdio};

fn qcs() -> Command {
    Command::new(env!("CARGO_BIN_EXE_qcs"))
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("qcs-cli-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir.join(name)
}

fn run(cmd: &mut Command) -> Output {
    cmd.output().expect("qcs runs")
}

/// Encode, inspect and decode a bundled photograph; the decoded picture has the asked size.
#[test]
fn encode_info_decode() {
    let rocket = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/rocket.png");
    let (file, png) = (scratch("rocket.qcs"), scratch("rocket-small.png"));
    let enc = run(qcs().args(["-q", "encode", rocket]).arg(&file));
    assert!(enc.status.success(), "{enc:?}");
    let info = run(qcs().arg("info").arg(&file));
    assert!(info.status.success(), "{info:?}");
    let text = String::from_utf8_lossy(&info.stdout);
    assert!(text.contains("480×320"), "{text}");
    let dec = run(qcs()
        .args(["-q", "decode"])
        .arg(&file)
        .arg(&png)
        .args(["--size", "97x61"]));
    assert!(dec.status.success(), "{dec:?}");
    let img = image::open(&png).expect("a PNG");
    assert_eq!((img.width(), img.height()), (97, 61));
}

/// Exit codes as documented in `qcs --help`: 3 for a malformed file, 1 for a missing one.
#[test]
fn exit_codes() {
    let bad = scratch("bad.qcs");
    std::fs::write(&bad, b"not a qcs file at all").expect("write");
    let out = run(qcs().arg("decode").arg(&bad).arg(scratch("bad.png")));
    assert_eq!(out.status.code(), Some(3), "{out:?}");
    let missing = run(qcs().arg("info").arg(scratch("no-such-file.qcs")));
    assert_eq!(missing.status.code(), Some(1), "{missing:?}");
    assert!(String::from_utf8_lossy(&missing.stderr).starts_with("qcs: error:"));
}

/// `qcs sites … | head -1`: the reader closes the pipe long before the end (the output is far
/// larger than a pipe buffer); qcs stops quietly with success, no panic, no error message.
#[test]
fn closed_stdout_ends_quietly() {
    let mut child = qcs()
        .args([
            "sites", "--width", "512", "--height", "512", "--count", "200000",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("qcs runs");
    let mut first = String::new();
    let mut reader = BufReader::new(child.stdout.take().expect("stdout"));
    reader.read_line(&mut first).expect("a line");
    assert_eq!(first, "index,x,y,n0,n1,n2,n3\n");
    drop(reader);
    let out = child.wait_with_output().expect("qcs ends");
    assert!(out.status.success(), "{out:?}");
    assert!(
        out.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );

    // `info` writes line by line: a pipe closed before it starts must not make it panic.
    let rocket = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/rocket.png");
    let file = scratch("pipe.qcs");
    assert!(run(qcs().args(["-q", "encode", rocket]).arg(&file))
        .status
        .success());
    let mut child = qcs()
        .arg("info")
        .arg(&file)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("qcs runs");
    drop(child.stdout.take());
    let out = child.wait_with_output().expect("qcs ends");
    assert!(out.status.success(), "{out:?}");
    assert!(
        out.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}
