//! The `qcs` binary as a shell user meets it: exit codes, and a reader that stops early.
#![cfg(feature = "cli")]

use std::io::{BufRead, BufReader};
use std::path::PathBuf;
use std::process::{Command, Output, Stdio};

/// The bundled photograph.
const ROCKET: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/rocket.png");

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
    let (file, png) = (scratch("rocket.qcs"), scratch("rocket-small.png"));
    let enc = run(qcs().args(["-q", "encode", ROCKET]).arg(&file));
    assert!(enc.status.success(), "{enc:?}");
    let info = run(qcs().arg("info").arg(&file));
    assert!(info.status.success(), "{info:?}");
    let text = String::from_utf8_lossy(&info.stdout);
    assert!(text.contains("480×320"), "{text}");
    assert!(text.contains("end: a complete file"), "{text}");
    let cut = scratch("rocket-cut.qcs");
    std::fs::write(&cut, &std::fs::read(&file).expect("read")[..40]).expect("write");
    let info = run(qcs().arg("info").arg(&cut));
    let text = String::from_utf8_lossy(&info.stdout);
    assert!(text.contains("end: inside chunk #0 'L' at byte "), "{text}");
    let dec = run(qcs()
        .args(["-q", "decode"])
        .arg(&file)
        .arg(&png)
        .args(["--size", "97x61"]));
    assert!(dec.status.success(), "{dec:?}");
    let img = image::open(&png).expect("a PNG");
    assert_eq!((img.width(), img.height()), (97, 61));
}

/// Runs `cmd` with `input` on its standard input.
fn piped(cmd: &mut Command, input: &[u8]) -> Output {
    use std::io::Write;
    let mut child = (cmd
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped()))
    .spawn()
    .expect("qcs runs");
    let mut stdin = child.stdin.take().expect("stdin");
    let input = input.to_vec();
    let writer = std::thread::spawn(move || stdin.write_all(&input));
    let out = child.wait_with_output().expect("qcs ends");
    writer.join().expect("writer").expect("qcs reads its input");
    out
}

/// `-` is standard input or output: a pipe encodes, decodes and inspects as files do, and a
/// cut pipe is a smaller picture.
#[test]
fn pipes_work_as_files() {
    let (file, png) = (scratch("pipe.qcs"), scratch("pipe.png"));
    assert!(run(qcs().args(["-q", "encode", ROCKET]).arg(&file))
        .status
        .success());
    let qcs_bytes = std::fs::read(&file).expect("read");
    let enc = piped(
        qcs().args(["-q", "encode", "-", "-"]),
        &std::fs::read(ROCKET).expect("read"),
    );
    assert!(enc.status.success(), "{enc:?}");
    assert!(enc.stdout == qcs_bytes, "the same file through a pipe");
    let size = ["--size", "97x61"];
    let dec = run(qcs().args(["-q", "decode"]).arg(&file).arg(&png).args(size));
    assert!(dec.status.success(), "{dec:?}");
    let dec = piped(
        qcs().args(["-q", "decode", "-", "-"]).args(size),
        &qcs_bytes,
    );
    assert!(dec.status.success(), "{dec:?}");
    assert!(
        dec.stdout == std::fs::read(&png).expect("read"),
        "the same PNG through a pipe"
    );
    let cut = &qcs_bytes[..2000];
    let dec = piped(qcs().args(["-q", "decode", "-", "-"]), cut);
    assert!(dec.status.success(), "{dec:?}");
    let img = image::load_from_memory(&dec.stdout).expect("a PNG");
    assert_eq!((img.width(), img.height()), (480, 320));
    let info = piped(qcs().args(["info", "-"]), cut);
    let text = String::from_utf8_lossy(&info.stdout);
    assert!(
        text.contains("(2000 bytes)") && text.contains("end: inside chunk"),
        "{text}"
    );
    let many = run(qcs()
        .args(["encode", "--out-dir"])
        .arg(scratch("pipe-dir"))
        .arg("-"));
    assert_eq!(many.status.code(), Some(2), "{many:?}");
    // On a terminal `-` is refused: util-linux `script` gives one, where it is installed
    // and can open a pseudo-terminal.
    let script = |cmd: &str| {
        Command::new("script")
            .args(["-qc", cmd, "/dev/null"])
            .output()
    };
    if script("tty").is_ok_and(|o| o.stdout.starts_with(b"/dev/")) {
        let on_tty = format!("{} decode {} -", env!("CARGO_BIN_EXE_qcs"), file.display());
        let out = script(&on_tty).expect("script runs");
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(
            text.contains("not writing binary data to a terminal"),
            "{text}"
        );
    }
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
    ends_quietly(child);

    // `info` writes line by line: a pipe closed before it starts must not make it panic.
    let file = rocket_qcs("pipe.qcs");
    let mut child = qcs()
        .arg("info")
        .arg(&file)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("qcs runs");
    drop(child.stdout.take());
    ends_quietly(child);

    // `demo` prints its table only once every file is written: a closed pipe loses none.
    let dir = scratch("demo-pipe");
    let mut child = qcs()
        .args(["demo", ROCKET])
        .arg(&dir)
        .stdout(Stdio::piped())
        .spawn()
        .expect("qcs runs");
    drop(child.stdout.take());
    assert!(child.wait().expect("qcs ends").success());
    let files = std::fs::read_dir(&dir).expect("demo dir").count();
    assert_eq!(files, 6, "rocket.qcs, four previews and the strip");
}

/// The child succeeds and says nothing on stderr.
fn ends_quietly(child: std::process::Child) {
    let out = child.wait_with_output().expect("qcs ends");
    assert!(out.status.success(), "{out:?}");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.is_empty(), "{err}");
}

fn code(cmd: &mut Command) -> (Option<i32>, String) {
    let out = run(cmd);
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn rocket_qcs(name: &str) -> PathBuf {
    let file = scratch(name);
    assert!(run(qcs().args(["-q", "encode", ROCKET]).arg(&file))
        .status
        .success());
    file
}

/// The last picture `qcs decode --frames` wrote into `dir` (their names sort in order).
fn last_frame(dir: &std::path::Path) -> PathBuf {
    let frames = std::fs::read_dir(dir).expect("frames");
    let paths = frames.map(|e| e.expect("entry").path());
    paths.max().expect("a frame")
}

/// An output much smaller than the image is a thumbnail (`DecodeOptions::thumbnail`), and
/// says so; `--no-thumbnail` renders every sample at its pixel centres.
#[test]
fn small_outputs_are_thumbnails() {
    let file = rocket_qcs("thumb.qcs");
    let bytes = std::fs::read(&file).expect("read");
    let total = qcs::container::inspect(&bytes)
        .header
        .expect("header")
        .total_samples;
    for plain in [false, true] {
        let png = scratch(&format!("thumb-{plain}.png"));
        let mut cmd = qcs();
        cmd.arg("decode")
            .arg(&file)
            .arg(&png)
            .args(["--size", "30x20"]);
        if plain {
            cmd.arg("--no-thumbnail");
        }
        let out = run(&mut cmd);
        assert!(out.status.success(), "{out:?}");
        let text = String::from_utf8_lossy(&out.stderr);
        let used = if plain { total } else { 16 * 30 * 20 };
        assert!(text.contains(&format!("from {used} samples")), "{text}");
        assert_eq!(text.contains("a thumbnail"), !plain, "{text}");
        let opts = qcs::DecodeOptions {
            thumbnail: !plain,
            ..qcs::DecodeOptions::thumbnail(30, 20)
        };
        let want = qcs::decode(&bytes, &opts).expect("decode").image.to_rgb8();
        assert!(image::open(&png).expect("a PNG").to_rgb8() == want);
        // `--frames` draws its pictures the same way: the last one is that picture.
        let dir = scratch(&format!("thumb-frames-{plain}"));
        let mut cmd = qcs();
        cmd.args(["-q", "decode"])
            .arg(&file)
            .arg("--frames")
            .arg(&dir);
        cmd.args(["--size", "30x20"]);
        if plain {
            cmd.arg("--no-thumbnail");
        }
        assert!(run(&mut cmd).status.success());
        let last = last_frame(&dir);
        assert!(
            image::open(&last).expect("a PNG").to_rgb8() == want,
            "{last:?}"
        );
    }
}

/// Sizes and counts beyond the default limits are refused with exit 4 before anything is
/// allocated, in every subcommand that takes them.
#[test]
fn limits_hold_in_every_subcommand() {
    let file = rocket_qcs("limits.qcs");
    let out = scratch("limits.png");
    for style in ["delaunay", "mosaic"] {
        let (c, err) = code(qcs().arg("render").arg(&file).arg(&out).args([
            "--style",
            style,
            "--size",
            "100000x100000",
        ]));
        assert_eq!(c, Some(4), "{style}: {err}");
    }
    let (c, err) = code(
        qcs()
            .arg("render")
            .arg(ROCKET)
            .arg(&out)
            .args(["--samples", "100000000"]),
    );
    assert_eq!(c, Some(4), "{err}");
    let (c, err) = code(qcs().args([
        "sites",
        "--width",
        "9",
        "--height",
        "9",
        "--count",
        "100000000",
    ]));
    assert_eq!(c, Some(4), "{err}");
    // A file `qcs decode` would refuse is not written: 2100² pixels at 1 sample per pixel
    // are more samples than the default limit (2^22).
    let big = scratch("limits-big.png");
    image::GrayImage::new(2100, 2100).save(&big).unwrap();
    let qcs_out = scratch("limits-big.qcs");
    let (c, err) = code(
        qcs()
            .arg("encode")
            .arg(&big)
            .arg(&qcs_out)
            .args(["--density", "1"]),
    );
    assert_eq!(c, Some(4), "{err}");
    assert!(err.contains("--density"), "{err}");
    assert!(!qcs_out.exists());
}

/// A file with more samples than the default limit decodes as a thumbnail, which needs only
/// its first levels; at full size it is refused (exit 4) with a hint. The file is flat grey:
/// its levels' predictive payloads are empty (every residual zero), 5 million samples in a
/// few hundred bytes.
#[test]
fn files_beyond_the_sample_limit_decode_as_thumbnails() {
    use qcs::container::{ContainerWriter, Header, Layout};
    let coding = qcs::coding::predictive::Params::default().coding();
    let header = Header::new(2500, 2500, Layout::Grey, 5_000_000, 127, coding);
    assert!(header.total_samples > qcs::Limits::default().max_samples);
    let mut w = ContainerWriter::new(Vec::new(), &header).expect("header");
    for _ in 0..header.level_count() {
        w.write_level(&[]).expect("level");
    }
    let file = scratch("over-limit.qcs");
    std::fs::write(&file, w.finish().expect("file")).expect("write");
    let png = scratch("over-limit.png");
    let out = run(qcs()
        .arg("decode")
        .arg(&file)
        .arg(&png)
        .args(["--size", "30x30"]));
    assert!(out.status.success(), "{out:?}");
    let text = String::from_utf8_lossy(&out.stderr);
    assert!(text.contains("from 14400 samples"), "{text}");
    let thumb = image::open(&png).expect("a PNG").to_luma8();
    assert_eq!(thumb.dimensions(), (30, 30));
    assert!(thumb.pixels().all(|p| p == thumb.get_pixel(0, 0)));
    let (c, err) = code(qcs().arg("decode").arg(&file).arg(&png));
    assert_eq!(c, Some(4), "{err}");
    assert!(err.contains("--size"), "{err}");
    // Streamed, as frames and as a GIF, the same: the last frame is the thumbnail.
    let dir = scratch("over-limit-frames");
    let out = run(qcs()
        .args(["-q", "decode"])
        .arg(&file)
        .arg("--frames")
        .arg(&dir)
        .args(["--size", "30x30"]));
    assert!(out.status.success(), "{out:?}");
    let last = last_frame(&dir);
    assert!(last.to_string_lossy().ends_with("-final.png"), "{last:?}");
    assert!(image::open(&last).expect("a PNG").to_luma8() == thumb);
    let gif = scratch("over-limit.gif");
    let out = run(qcs()
        .args(["-q", "preview"])
        .arg(&file)
        .arg(&gif)
        .args(["--size", "30x30"]));
    assert!(out.status.success(), "{out:?}");
}

/// Nonsense numbers are usage errors (exit 2), not a silent one-sample file or exit 1.
#[test]
fn nonsense_numbers_are_usage_errors() {
    let file = rocket_qcs("numbers.qcs");
    let out = scratch("numbers.png");
    for bad in [["--density", "0"], ["--density", "nan"], ["--samples", "0"]] {
        let (c, err) = code(
            qcs()
                .args(["encode", ROCKET])
                .arg(scratch("n.qcs"))
                .args(bad),
        );
        assert_eq!(c, Some(2), "{bad:?}: {err}");
    }
    for bad in [["--scale", "0"], ["--scale", "inf"], ["--every", "0"]] {
        let mut cmd = qcs();
        cmd.arg("decode").arg(&file).arg(&out).args(bad);
        if bad[0] == "--every" {
            cmd.arg("--frames").arg(scratch("frames-0"));
        }
        let (c, err) = code(&mut cmd);
        assert_eq!(c, Some(2), "{bad:?}: {err}");
    }
    let (c, err) = code(
        qcs()
            .args(["sites", "--width", "9", "--height", "9", "--count", "3"])
            .args(["--sampler", "bogus"]),
    );
    assert_eq!(c, Some(2), "{err}");
}

/// No command destroys or half-writes a file: the input is never the output, two inputs
/// never share an output, a failed write leaves no file, a grey picture can be saved in a
/// format without grey, and a format recognised by content needs no extension.
#[test]
fn files_are_written_whole_or_not_at_all() {
    let photo = scratch("photo.png");
    std::fs::copy(ROCKET, &photo).expect("copy");
    let before = std::fs::read(&photo).expect("read");
    let (c, _) = code(qcs().arg("encode").arg(&photo).arg(&photo));
    assert_eq!(c, Some(2));
    assert_eq!(
        std::fs::read(&photo).expect("read"),
        before,
        "the input survives"
    );

    let (a, b) = (scratch("a"), scratch("b"));
    for d in [&a, &b] {
        std::fs::create_dir_all(d).expect("dir");
        std::fs::copy(ROCKET, d.join("x.png")).expect("copy");
    }
    let dir = scratch("out-dir");
    let (c, err) = code(
        qcs()
            .arg("encode")
            .arg(a.join("x.png"))
            .arg(b.join("x.png"))
            .arg("--out-dir")
            .arg(&dir),
    );
    assert_eq!(c, Some(2), "{err}");
    assert!(err.contains("would both be written"), "{err}");

    // Content, not extension, says what an input is.
    let bare = scratch("no-extension");
    std::fs::copy(ROCKET, &bare).expect("copy");
    assert!(run(qcs()
        .args(["-q", "encode"])
        .arg(&bare)
        .arg(scratch("bare.qcs")))
    .status
    .success());

    // A grey file decodes to GIF (widened to RGB); an unknown extension leaves no file.
    let grey = scratch("grey.png");
    image::GrayImage::from_pixel(30, 20, image::Luma([99]))
        .save(&grey)
        .expect("save");
    let grey_qcs = scratch("grey.qcs");
    assert!(run(qcs().args(["-q", "encode"]).arg(&grey).arg(&grey_qcs))
        .status
        .success());
    let gif = scratch("grey.gif");
    assert!(run(qcs().args(["-q", "decode"]).arg(&grey_qcs).arg(&gif))
        .status
        .success());
    assert_eq!(image::open(&gif).expect("a GIF").width(), 30);
    let odd = scratch("grey.xyz");
    assert_ne!(
        code(qcs().arg("decode").arg(&grey_qcs).arg(&odd)).0,
        Some(0)
    );
    assert!(!odd.exists());
}

/// A library error is printed once, not once per level of its cause chain.
#[test]
fn errors_are_printed_once() {
    let (c, err) = code(qcs().arg("info").arg(ROCKET));
    assert_eq!(c, Some(3));
    let line = err.lines().next().unwrap_or_default();
    assert_eq!(line.matches("bad magic byte").count(), 1, "{line}");
}

/// `decode --frames --bytes K` stops at K bytes, as a cut download would.
#[test]
fn frames_stop_at_the_byte_budget() {
    let file = rocket_qcs("frames.qcs");
    let dir = scratch("frames-budget");
    let ok = run(qcs()
        .args(["-q", "decode"])
        .arg(&file)
        .arg("--frames")
        .arg(&dir)
        .args(["--bytes", "600"]));
    assert!(ok.status.success(), "{ok:?}");
    let names: Vec<String> = std::fs::read_dir(&dir)
        .expect("frames")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    assert!(!names.is_empty());
    assert!(names.iter().all(|n| n.contains("preview")), "{names:?}");
}

/// A camera's picture: a 24 × 16 PNG, left half red and right half blue, whose Exif says
/// "rotate 90° clockwise" to be upright, with an ICC profile that is not sRGB.
fn camera_png(name: &str, icc: &[u8]) -> PathBuf {
    use image::ImageEncoder;
    let img = image::RgbImage::from_fn(24, 16, |x, _| {
        image::Rgb(if x < 12 { [220, 20, 20] } else { [20, 20, 220] })
    });
    // Big-endian TIFF header, one IFD entry: Orientation (0x0112), SHORT, 1 value: 6.
    let exif = [
        b'M', b'M', 0, 42, 0, 0, 0, 8, 0, 1, 0x01, 0x12, 0, 3, 0, 0, 0, 1, 0, 6, 0, 0, 0, 0, 0, 0,
    ];
    let mut bytes = Vec::new();
    let mut enc = image::codecs::png::PngEncoder::new(&mut bytes);
    enc.set_icc_profile(icc.to_vec()).expect("PNG holds ICC");
    enc.set_exif_metadata(exif.to_vec())
        .expect("PNG holds Exif");
    enc.write_image(img.as_raw(), 24, 16, image::ExtendedColorType::Rgb8)
        .expect("PNG");
    let path = scratch(name);
    std::fs::write(&path, bytes).expect("write");
    path
}

/// The ICC profile of a PNG, if any.
fn png_icc(path: &PathBuf) -> Option<Vec<u8>> {
    use image::ImageDecoder;
    let file = std::io::BufReader::new(std::fs::File::open(path).expect("open"));
    let mut dec = image::codecs::png::PngDecoder::new(file).expect("a PNG");
    dec.icc_profile().expect("readable")
}

/// `qcs encode` stores a photo upright (its Exif orientation applied) with its colour
/// profile, and `qcs decode` writes the profile back, unless `--strip-icc` drops it.
#[test]
fn orientation_and_colour_profile_survive_a_round_trip() {
    let icc = b"a Display P3 profile, as far as this test cares".to_vec();
    let src = camera_png("camera.png", &icc);
    let (file, back) = (scratch("camera.qcs"), scratch("camera-back.png"));
    let enc = run(qcs().args(["encode", "--lossless"]).arg(&src).arg(&file));
    assert!(enc.status.success(), "{enc:?}");
    let said = String::from_utf8_lossy(&enc.stderr);
    assert!(
        said.contains(&format!("its {}-byte ICC profile", icc.len())),
        "{said}"
    );
    let dec = run(qcs().args(["-q", "decode"]).arg(&file).arg(&back));
    assert!(dec.status.success(), "{dec:?}");
    let img = image::open(&back).expect("a PNG").to_rgb8();
    // Upright: 16 wide, 24 high, the left half (red) now on top.
    assert_eq!(img.dimensions(), (16, 24));
    let (top, bottom) = (img.get_pixel(8, 3).0, img.get_pixel(8, 20).0);
    assert!(top[0] > 180 && top[2] < 60, "top {top:?}");
    assert!(bottom[2] > 180 && bottom[0] < 60, "bottom {bottom:?}");
    assert_eq!(png_icc(&back), Some(icc.clone()));

    // Dropped on request.
    let stripped = scratch("camera-stripped.qcs");
    let enc = run(qcs()
        .args(["-q", "encode", "--strip-icc"])
        .arg(&src)
        .arg(&stripped));
    assert!(enc.status.success(), "{enc:?}");
    let dec = run(qcs().args(["-q", "decode"]).arg(&stripped).arg(&back));
    assert!(dec.status.success(), "{dec:?}");
    assert_eq!(png_icc(&back), None);

    // A format without profiles: written, with a warning.
    let bmp = scratch("camera-back.bmp");
    let dec = run(qcs().arg("decode").arg(&file).arg(&bmp));
    assert!(dec.status.success(), "{dec:?}");
    assert!(String::from_utf8_lossy(&dec.stderr).contains("cannot hold the file's ICC"));
}
