//! The `qcs` binary as a shell user meets it: exit codes, and a reader that stops early.

use std::io::{BufRead, BufReader};
use std::path::PathBuf;
use std::process::{Command, Output, Stdio};

/// The bundled photograph.
const ROCKET: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../assets/rocket.png");

fn qcs() -> Command {
    Command::new(env!("CARGO_BIN_EXE_qcs"))
}

/// A path in this run's scratch folder, in the target directory (emptied at the run's start).
fn scratch(name: &str) -> PathBuf {
    static DIR: std::sync::OnceLock<PathBuf> = std::sync::OnceLock::new();
    DIR.get_or_init(|| {
        let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("cli");
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("scratch dir");
        dir
    })
    .join(name)
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
    std::fs::write(&cut, &std::fs::read(&file).expect("read")[..20]).expect("write");
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
    // Thumbnails of the levels' samples: a file of levels only.
    let file = scratch("thumb.qcs");
    assert!(run(qcs()
        .args(["-q", "encode", "--levels-only", ROCKET])
        .arg(&file))
    .status
    .success());
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
    let (c, err) =
        code(
            qcs()
                .arg("encode")
                .arg(&big)
                .arg(&qcs_out)
                .args(["--levels-only", "--density", "1"]),
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
    // A picture is written beside its name and renamed when whole (the GIF above was
    // written twice, the second time widened): nothing of that is left.
    let folder = gif.parent().expect("a folder");
    let parts: Vec<_> = std::fs::read_dir(folder)
        .expect("list")
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().ends_with(".part"))
        .collect();
    assert!(parts.is_empty(), "{parts:?}");
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

/// `decode --frames` and `preview` make a picture where each level and each refinement layer
/// ends: as many as the file has level and `R` chunks.
#[test]
fn frames_at_every_level_and_layer() {
    let file = rocket_qcs("frames-layers.qcs");
    let ins = qcs::container::inspect(&std::fs::read(&file).expect("read"));
    let parts = ins.chunks.iter();
    let parts = parts
        .filter(|c| c.level.is_some() || c.layer.is_some())
        .count();
    assert!(ins.chunks.iter().filter(|c| c.layer.is_some()).count() > 2);
    let dir = scratch("frames-layers");
    let ok = run(qcs()
        .args(["-q", "decode"])
        .arg(&file)
        .arg("--frames")
        .arg(&dir));
    assert!(ok.status.success(), "{ok:?}");
    assert_eq!(std::fs::read_dir(&dir).expect("frames").count(), parts);
    let gif = scratch("frames-layers.gif");
    let ok = run(qcs().args(["-q", "preview"]).arg(&file).arg(&gif));
    assert!(ok.status.success(), "{ok:?}");
    assert_eq!(gif_frames(&gif), parts);
}

/// A camera's Exif: a big-endian TIFF header and one IFD of two entries: Make (0x010F),
/// ASCII, "QcsCam" at byte 38; Orientation (0x0112), SHORT, `orientation`.
fn camera_exif(orientation: u8) -> Vec<u8> {
    let mut e = vec![b'M', b'M', 0, 42, 0, 0, 0, 8, 0, 2];
    e.extend_from_slice(&[0x01, 0x0f, 0, 2, 0, 0, 0, 7, 0, 0, 0, 38]);
    e.extend_from_slice(&[0x01, 0x12, 0, 3, 0, 0, 0, 1, 0, orientation, 0, 0]);
    e.extend_from_slice(&[0, 0, 0, 0]);
    e.extend_from_slice(b"QcsCam\0");
    e
}

/// A camera's picture: a 24 × 16 PNG, left half red and right half blue, whose Exif says
/// "rotate 90° clockwise" to be upright, with an ICC profile that is not sRGB.
fn camera_png(name: &str, icc: &[u8]) -> PathBuf {
    use image::ImageEncoder;
    let img = image::RgbImage::from_fn(24, 16, |x, _| {
        image::Rgb(if x < 12 { [220, 20, 20] } else { [20, 20, 220] })
    });
    let exif = camera_exif(6);
    let mut bytes = Vec::new();
    let mut enc = image::codecs::png::PngEncoder::new(&mut bytes);
    enc.set_icc_profile(icc.to_vec()).expect("PNG holds ICC");
    enc.set_exif_metadata(exif).expect("PNG holds Exif");
    enc.write_image(img.as_raw(), 24, 16, image::ExtendedColorType::Rgb8)
        .expect("PNG");
    let path = scratch(name);
    std::fs::write(&path, bytes).expect("write");
    path
}

/// The ICC profile and the Exif of a PNG, if any.
fn png_metadata(path: &PathBuf) -> (Option<Vec<u8>>, Option<Vec<u8>>) {
    use image::ImageDecoder;
    let file = std::io::BufReader::new(std::fs::File::open(path).expect("open"));
    let mut dec = image::codecs::png::PngDecoder::new(file).expect("a PNG");
    let icc = dec.icc_profile().expect("readable");
    (icc, dec.exif_metadata().expect("readable"))
}

/// `qcs encode` stores a photo upright (its Exif orientation applied) with its colour
/// profile and its Exif (orientation now 1), and `qcs decode` writes them back, unless
/// `--strip-icc` or `--strip-exif` drops them.
#[test]
fn orientation_and_colour_profile_survive_a_round_trip() {
    let icc = b"a Display P3 profile, as far as this test cares".to_vec();
    let src = camera_png("camera.png", &icc);
    let (file, back) = (scratch("camera.qcs"), scratch("camera-back.png"));
    let enc = run(qcs().args(["encode", "--lossless"]).arg(&src).arg(&file));
    assert!(enc.status.success(), "{enc:?}");
    let said = String::from_utf8_lossy(&enc.stderr);
    assert!(
        said.contains(&format!(
            "its {}-byte ICC profile and 45-byte Exif",
            icc.len()
        )),
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
    assert_eq!(
        png_metadata(&back),
        (Some(icc.clone()), Some(camera_exif(1)))
    );
    // Every frame carries the profile (it follows level 0, and so does the first frame's
    // cut); the last, the whole file, the Exif.
    let frames = scratch("camera-frames");
    let dec = run(qcs()
        .args(["-q", "decode"])
        .arg(&file)
        .arg("--frames")
        .arg(&frames));
    assert!(dec.status.success(), "{dec:?}");
    let mut paths: Vec<_> = (std::fs::read_dir(&frames).expect("frames"))
        .map(|e| e.expect("entry").path())
        .collect();
    paths.sort();
    for p in &paths {
        assert_eq!(png_metadata(p).0, Some(icc.clone()), "{}", p.display());
    }
    assert_eq!(png_metadata(&last_frame(&frames)).1, Some(camera_exif(1)));

    // Dropped on request.
    let stripped = scratch("camera-stripped.qcs");
    let enc = run(qcs()
        .args(["-q", "encode", "--strip-icc"])
        .arg(&src)
        .arg(&stripped));
    assert!(enc.status.success(), "{enc:?}");
    let dec = run(qcs().args(["-q", "decode"]).arg(&stripped).arg(&back));
    assert!(dec.status.success(), "{dec:?}");
    assert_eq!(png_metadata(&back), (None, Some(camera_exif(1))));
    let enc = run(qcs()
        .args(["-q", "encode", "--strip-exif"])
        .arg(&src)
        .arg(&stripped));
    assert!(enc.status.success(), "{enc:?}");
    let dec = run(qcs().args(["-q", "decode"]).arg(&stripped).arg(&back));
    assert!(dec.status.success(), "{dec:?}");
    assert_eq!(png_metadata(&back), (Some(icc.clone()), None));

    // A size the metadata alone exceeds: written, with a warning.
    let (c, err) = code(
        qcs()
            .args(["encode", "--target-size", "60"])
            .arg(&src)
            .arg(&stripped),
    );
    assert_eq!(c, Some(0), "{err}");
    assert!(err.contains("over --target-size 60"), "{err}");

    // A format without profiles: written, with a warning.
    let bmp = scratch("camera-back.bmp");
    let dec = run(qcs().arg("decode").arg(&file).arg(&bmp));
    assert!(dec.status.success(), "{dec:?}");
    let said = String::from_utf8_lossy(&dec.stderr);
    assert!(said.contains("cannot hold the file's ICC"), "{said}");
    assert!(said.contains("cannot hold the file's Exif"), "{said}");
}

/// Waits for `child` (`wait4`, as `Child::wait` would) and returns its exit code and peak
/// resident memory in bytes.
#[allow(unsafe_code)]
fn wait_peak(child: std::process::Child) -> (Option<i32>, u64) {
    let mut status = 0;
    // SAFETY: `rusage` is plain data, all zeros valid; `wait4` writes both out-parameters.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    let pid = child.id() as libc::pid_t;
    let r = unsafe { libc::wait4(pid, &mut status, 0, &mut usage) };
    assert_eq!(r, pid, "wait4");
    let code = libc::WIFEXITED(status).then(|| libc::WEXITSTATUS(status));
    (code, usage.ru_maxrss as u64 * 1024)
}

/// Shrinks a pipe's buffer to one page, so that what a reader took is what was written,
/// give or take 4 KiB.
#[allow(unsafe_code)]
fn small_pipe(stdin: &std::process::ChildStdin) {
    use std::os::fd::AsRawFd;
    // SAFETY: `fcntl` on a file descriptor this process owns; no memory is passed.
    let r = unsafe { libc::fcntl(stdin.as_raw_fd(), libc::F_SETPIPE_SZ, 4096) };
    assert!(r >= 4096, "F_SETPIPE_SZ");
}

/// Runs `cmd` with `source` (then zeros, without end) written to its standard input until it
/// stops reading; returns its exit code, peak memory, standard error, the bytes it was
/// given, and the time it took.
fn fed(cmd: &mut Command, source: &[u8]) -> (Option<i32>, u64, String, u64, f64) {
    use std::io::{Read, Write};
    let start = std::time::Instant::now();
    let mut child = cmd
        .stdin(Stdio::piped())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("qcs runs");
    let mut stdin = child.stdin.take().expect("stdin");
    small_pipe(&stdin);
    let source = source.to_vec();
    let writer = std::thread::spawn(move || {
        let mut written = 0u64;
        let zeros = [0u8; 512];
        for piece in source.chunks(512).chain(std::iter::repeat(&zeros[..])) {
            match stdin.write_all(piece) {
                Ok(()) => written += piece.len() as u64,
                Err(_) => return written,
            }
            // A runaway reader is stopped at 4 GiB.
            if written > 4 << 30 {
                return written;
            }
        }
        written
    });
    let mut err = String::new();
    let mut stderr = child.stderr.take().expect("stderr");
    let (code, peak) = wait_peak(child);
    stderr.read_to_string(&mut err).expect("stderr");
    let written = writer.join().expect("writer");
    (code, peak, err, written, start.elapsed().as_secs_f64())
}

/// 64 MB: more than qcs needs to refuse any input, far less than the input.
const BOUNDED: u64 = 64 << 20;

/// A stream of zeros is refused at its first block, in bounded memory and time, by every
/// subcommand that reads a .qcs file, with `--bytes` too.
#[test]
fn a_stream_of_zeros_is_refused_at_once() {
    let gif = scratch("zeros.gif");
    let png = scratch("zeros.png");
    let cmd = |args: &[&std::ffi::OsStr]| {
        let mut c = qcs();
        c.args(args);
        c
    };
    let (dash, png_, gif_) = ("-".as_ref(), png.as_os_str(), gif.as_os_str());
    let mut cmds = [
        cmd(&["decode".as_ref(), dash, png_]),
        cmd(&[
            "decode".as_ref(),
            dash,
            png_,
            "--bytes".as_ref(),
            "2048".as_ref(),
        ]),
        cmd(&["info".as_ref(), dash]),
        cmd(&["preview".as_ref(), dash, gif_]),
        cmd(&["render".as_ref(), dash, png_]),
    ];
    for cmd in &mut cmds {
        let what = format!("{cmd:?}");
        let (code, peak, err, written, secs) = fed(cmd, b"");
        assert_eq!(code, Some(3), "{what}: {err}");
        // `render` takes images too: zeros are neither.
        let says = match what.contains("render") {
            true => "format could not be determined",
            false => "bad magic byte 0x00 at byte 0",
        };
        assert!(err.contains(says), "{what}: {err}");
        assert!(peak < BOUNDED, "{what}: {peak} bytes at peak");
        // One block read (64 KiB), the pipe's page, the writer's piece.
        assert!(
            written <= (64 << 10) + 4096 + 512,
            "{what}: {written} bytes taken"
        );
        assert!(secs < 10.0, "{what}: {secs} s");
    }
    assert!(!png.exists() && !gif.exists());
}

/// A huge file is refused as soon as it breaks the format (a 2 GiB file of zeros: at byte
/// 0), or, if it goes on being well formed, at `--max-input`, having held no more.
#[test]
fn a_huge_file_is_refused_in_bounded_memory() {
    let zeros = scratch("huge-zeros.qcs");
    let f = std::fs::File::create(&zeros).expect("create");
    f.set_len(2 << 30).expect("a sparse 2 GiB file");
    drop(f);
    let png = scratch("huge.png");
    for args in [&["decode"][..], &["info"], &["render"]] {
        let mut cmd = qcs();
        cmd.args(args).arg(&zeros);
        if args[0] != "info" {
            cmd.arg(&png);
        }
        let start = std::time::Instant::now();
        let child = cmd.stderr(Stdio::piped()).spawn().expect("qcs runs");
        let (code, peak) = wait_peak(child);
        assert_eq!(code, Some(3), "{args:?}");
        assert!(peak < BOUNDED, "{args:?}: {peak} bytes at peak");
        assert!(start.elapsed().as_secs_f64() < 10.0, "{args:?}");
    }
    // A whole file, then an unknown ancillary chunk ('z') of 1 GiB: well formed for as long
    // as it lasts, so only the input cap stops it.
    let mut head = std::fs::read(rocket_qcs("huge-head.qcs")).expect("read");
    head.extend_from_slice(&[b'z', 0x80, 0x80, 0x80, 0x80, 0x04]); // varint 2^30
    let long = scratch("huge-chunk.qcs");
    std::fs::write(&long, &head).expect("write");
    let f = std::fs::OpenOptions::new()
        .append(true)
        .open(&long)
        .expect("open");
    f.set_len(head.len() as u64 + (1 << 30) + 4)
        .expect("sparse");
    drop(f);
    let child = qcs()
        .args(["decode", "--max-input", "8M"])
        .arg(&long)
        .arg(&png)
        .stderr(Stdio::piped())
        .spawn()
        .expect("qcs runs");
    let (code, peak) = wait_peak(child);
    assert_eq!(code, Some(4));
    assert!(peak < BOUNDED, "{peak} bytes at peak");
    // The default cap (64 MiB) holds as well: refused, and no more held than the cap.
    let (c, err) = code_of(qcs().arg("decode").arg(&long).arg(&png));
    assert_eq!(c, Some(4), "{err}");
    assert!(err.contains("--max-input 67108864"), "{err}");
    // Lifted, the chunk is read to its end and its CRC found wrong.
    let (c, err) = code_of(qcs().args(["info", "--max-input", "none"]).arg(&long));
    assert_eq!(c, Some(3), "{err}");
    assert!(err.contains("CRC mismatch"), "{err}");
    // Each part of the cause chain once: "… is damaged: malformed file: chunk … CRC mismatch …".
    assert_eq!(err.matches("malformed file").count(), 1, "{err}");
    assert_eq!(err.matches("CRC mismatch").count(), 1, "{err}");
    assert!(!png.exists());
}

/// `--bytes K` reads at most K bytes from a pipe: the writer, behind a one-page pipe, gets
/// rid of no more than K and a page, and the picture is the one of the file's first K bytes.
#[test]
fn the_byte_budget_is_all_that_is_read_from_a_pipe() {
    let file = rocket_qcs("budget.qcs");
    let bytes = std::fs::read(&file).expect("read");
    for k in [0usize, 5, 2048, 6000] {
        let png = scratch(&format!("budget-{k}.png"));
        let (code, _, err, written, _) = fed(
            qcs()
                .args(["decode", "-"])
                .arg(&png)
                .args(["--bytes", &k.to_string()]),
            &bytes,
        );
        assert_eq!(code, Some(0), "{err}");
        assert!(
            written as usize <= k + 4096 + 512,
            "--bytes {k}: {written} bytes taken"
        );
        let got = image::open(&png).expect("a PNG");
        if k < 9 {
            // Inside the header: a neutral grey picture, not an error.
            assert_eq!(got.to_luma8().as_raw(), &[128]);
            assert!(err.contains("end inside the header"), "{err}");
        } else {
            let opts = qcs::DecodeOptions {
                max_bytes: Some(k),
                thumbnail: true,
                ..Default::default()
            };
            let want = qcs::decode(&bytes, &opts).expect("decode");
            assert!(got.to_rgb8() == want.image.to_rgb8(), "--bytes {k}");
        }
    }
}

fn code_of(cmd: &mut Command) -> (Option<i32>, String) {
    code(cmd)
}

/// No command writes over a file whose name says it is something else: .qcs data only into
/// `.qcs` names (or `-o NAME` that is not an image format's), a GIF only into `.gif`, an
/// image only into an image format's name.
#[test]
fn no_file_is_overwritten_with_another_kind() {
    let file = rocket_qcs("kinds.qcs");
    let (a, b) = (scratch("kinds-a.png"), scratch("kinds-b.png"));
    std::fs::copy(ROCKET, &a).expect("copy");
    std::fs::copy(ROCKET, &b).expect("copy");
    let photo = std::fs::read(ROCKET).expect("read");
    let qcs_bytes = std::fs::read(&file).expect("read");
    let p_png = scratch("kinds-p.png");
    std::fs::copy(ROCKET, &p_png).expect("copy");
    let other_qcs = scratch("kinds-other.qcs");
    std::fs::write(&other_qcs, &qcs_bytes).expect("write");
    let refused: Vec<(Vec<std::ffi::OsString>, &PathBuf)> = vec![
        (
            vec!["encode".into(), a.clone().into(), b.clone().into()],
            &b,
        ),
        (
            vec![
                "encode".into(),
                a.clone().into(),
                b.clone().into(),
                other_qcs.clone().into(),
            ],
            &b,
        ),
        (
            vec![
                "encode".into(),
                a.clone().into(),
                "-o".into(),
                b.clone().into(),
            ],
            &b,
        ),
        (
            vec!["preview".into(), file.clone().into(), p_png.clone().into()],
            &p_png,
        ),
        (
            vec![
                "decode".into(),
                file.clone().into(),
                other_qcs.clone().into(),
            ],
            &other_qcs,
        ),
        (
            vec![
                "render".into(),
                file.clone().into(),
                other_qcs.clone().into(),
            ],
            &other_qcs,
        ),
    ];
    for (args, victim) in refused {
        let before = std::fs::read(victim).expect("read");
        let (c, err) = code(qcs().args(&args));
        assert_eq!(c, Some(2), "{args:?}: {err}");
        assert_eq!(std::fs::read(victim).expect("read"), before, "{args:?}");
    }
    assert_eq!(std::fs::read(&b).expect("read"), photo);
    // What is allowed: -o with a name that is no image format's, `.QCS`, a .gif preview.
    let bin = scratch("kinds.bin");
    let out = run(qcs().args(["-q", "encode"]).arg(&a).arg("-o").arg(&bin));
    assert!(out.status.success(), "{out:?}");
    assert_eq!(std::fs::read(&bin).expect("read"), qcs_bytes);
    let upper = scratch("kinds.QCS");
    assert!(run(qcs().args(["-q", "encode"]).arg(&a).arg(&upper))
        .status
        .success());
    assert_eq!(std::fs::read(&upper).expect("read"), qcs_bytes);
}

/// Every mistake on the command line exits 2 with a message that says what to do, before
/// any work; and each exit code the README promises is what the tool returns.
#[test]
fn every_usage_error_exits_2_and_every_exit_code_is_true() {
    let file = rocket_qcs("usage.qcs");
    let png = scratch("usage.png");
    let empty_dir = scratch("usage-empty-dir");
    std::fs::create_dir_all(&empty_dir).expect("dir");
    let s = |v: &[&str]| -> Vec<std::ffi::OsString> { v.iter().map(Into::into).collect() };
    let f = file.as_os_str().to_owned();
    let p = png.as_os_str().to_owned();
    let with = |mut v: Vec<std::ffi::OsString>, at: usize, x: &std::ffi::OsStr| {
        v.insert(at, x.to_owned());
        v
    };
    let usage: Vec<(Vec<std::ffi::OsString>, &str)> = vec![
        (s(&["encode", ROCKET]), "no output"),
        (s(&["encode", ROCKET, ROCKET, "o.qcs"]), "3 paths"),
        (with(s(&["decode", "o.xyz"]), 1, &f), "unknown image format"),
        (with(s(&["decode", "o.avif"]), 1, &f), "qcs writes no Avif"),
        (
            s(&["sites", "--width", "0", "--height", "5", "--count", "3"]),
            "from 1 to 65535",
        ),
        (
            with(with(s(&["decode", "--samples", "0"]), 1, &f), 2, &p),
            "at least 1",
        ),
        (
            with(with(s(&["decode", "--samples", "-5"]), 1, &f), 2, &p),
            "at least 1, got \"-5\"",
        ),
        (
            with(with(s(&["decode", "--size", "0x5"]), 1, &f), 2, &p),
            "expected WxH",
        ),
        (
            with(with(s(&["decode", "--size", "x"]), 1, &f), 2, &p),
            "expected WxH",
        ),
        (
            s(&["encode", ROCKET, "n.qcs", "--samples", "100000000000"]),
            "more than its 153600 pixels",
        ),
        (
            with(s(&["encode", "again.qcs"]), 1, &f),
            "is a .qcs file already: decode it",
        ),
        (
            with(s(&["encode", "--out-dir", "x"]), 1, empty_dir.as_os_str()),
            "nothing to encode",
        ),
        (
            with(s(&["preview", "p.gif", "--every", "1"]), 1, &f),
            "more than --max-frames 100",
        ),
    ];
    for (args, says) in usage {
        let (c, err) = code(qcs().args(&args));
        assert_eq!(c, Some(2), "{args:?}: {err}");
        assert!(err.contains(says), "{args:?}: {err}");
        assert!(!err.contains("'-- -5'"), "{args:?}: {err}");
    }
    // 0: success; 1: I/O (a missing input, a missing output folder); 3: malformed; 4: a limit.
    assert_eq!(
        code(qcs().args(["-q", "decode"]).arg(&file).arg(&png)).0,
        Some(0)
    );
    let (c, err) = code(qcs().arg("decode").arg(scratch("no-such.qcs")).arg(&png));
    assert_eq!(c, Some(1), "{err}");
    let (c, err) = code(qcs().arg("decode").arg(&file).arg(scratch("no-dir/o.png")));
    assert_eq!(c, Some(1), "{err}");
    assert!(err.contains("there is no folder"), "{err}");
    let (c, err) = code(qcs().arg("decode").arg(ROCKET).arg(&png));
    assert_eq!(c, Some(3), "{err}");
    let (c, err) = code(
        qcs()
            .args(["decode", "--max-pixels", "1000"])
            .arg(&file)
            .arg(&png),
    );
    assert_eq!(c, Some(4), "{err}");
    let (c, err) = code(
        qcs()
            .args(["decode", "--max-input", "1K"])
            .arg(&file)
            .arg(&png),
    );
    assert_eq!(c, Some(4), "{err}");
    // Binary data to a terminal is a usage error, before the work.
    let script = |cmd: &str| {
        Command::new("script")
            .args(["-qec", cmd, "/dev/null"])
            .output()
    };
    if script("tty").is_ok_and(|o| o.stdout.starts_with(b"/dev/")) {
        let on_tty = format!("{} decode {} -", env!("CARGO_BIN_EXE_qcs"), file.display());
        let out = script(&on_tty).expect("script runs");
        assert_eq!(out.status.code(), Some(2), "{out:?}");
    }
}

/// A missing output folder is reported before the input is read: with an input that never
/// comes, qcs still ends at once.
#[test]
fn a_missing_output_folder_is_found_before_the_work() {
    let mut child = qcs()
        .args(["decode", "-"])
        .arg(scratch("no-such-dir/o.png"))
        .stdin(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("qcs runs");
    let _stdin = child.stdin.take();
    let start = std::time::Instant::now();
    loop {
        if let Some(status) = child.try_wait().expect("wait") {
            assert_eq!(status.code(), Some(1));
            break;
        }
        assert!(start.elapsed().as_secs() < 20, "qcs waits for its input");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
}

/// A file that ends inside its header is a picture with nothing in it: neutral grey at the
/// asked size, exit 0 (spec/format.md, Truncation), for 0, 1 and 5 bytes and `--bytes 0`,
/// in decode, preview and render; `info` says where it ends.
#[test]
fn a_cut_header_is_a_grey_picture() {
    let file = rocket_qcs("cut-header.qcs");
    let bytes = std::fs::read(&file).expect("read");
    for n in [0usize, 1, 5] {
        let cut = scratch(&format!("cut-header-{n}.qcs"));
        std::fs::write(&cut, &bytes[..n]).expect("write");
        let png = scratch(&format!("cut-header-{n}.png"));
        let (c, err) = code(
            qcs()
                .arg("decode")
                .arg(&cut)
                .arg(&png)
                .args(["--size", "6x4"]),
        );
        assert_eq!(c, Some(0), "{n}: {err}");
        let img = image::open(&png).expect("a PNG").to_luma8();
        assert_eq!(img.dimensions(), (6, 4));
        assert!(img.pixels().all(|p| p.0 == [128]));
        let (c, err) = code(qcs().arg("info").arg(&cut));
        assert_eq!(c, Some(0), "{n}: {err}");
        let gif = scratch(&format!("cut-header-{n}.gif"));
        assert_eq!(code(qcs().arg("preview").arg(&cut).arg(&gif)).0, Some(0));
        assert_eq!(gif_frames(&gif), 1);
        let (c, err) = code(qcs().arg("render").arg(&cut).arg(&png));
        assert_eq!(c, Some(0), "{n}: {err}");
    }
    let png = scratch("cut-header-b0.png");
    let (c, err) = code(
        qcs()
            .arg("decode")
            .arg(&file)
            .arg(&png)
            .args(["--bytes", "0"]),
    );
    assert_eq!(c, Some(0), "{err}");
    assert!(err.contains("neutral grey 1×1"), "{err}");
}

/// `qcs demo` of an image whose file is so small that its first 1 % ends inside the header:
/// that preview is neutral grey, as `qcs decode` draws such a cut, not an error (it was exit
/// 3, "malformed", from the library's `NeedMoreData`).
#[test]
fn a_demo_whose_first_cut_ends_inside_the_header_draws_grey() {
    let png = scratch("demo-tiny.png");
    image::RgbImage::from_pixel(2, 2, image::Rgb([200, 100, 50]))
        .save(&png)
        .expect("save");
    let dir = scratch("demo-tiny");
    let out = run(qcs().arg("demo").arg(&png).arg(&dir));
    let (text, err) = (
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
    );
    assert!(out.status.success(), "{err}");
    assert!(!err.contains("malformed"), "{err}");
    assert!(
        text.contains("neutral grey: the bytes end inside the header"),
        "{text}"
    );
    let first = image::open(dir.join("demo-tiny-001pct.png")).expect("a PNG");
    assert!(first.to_rgb8().pixels().all(|p| p.0 == [128; 3]));
    let whole = image::open(dir.join("demo-tiny-100pct.png")).expect("a PNG");
    assert!(whole.to_rgb8().pixels().all(|p| p.0 != [128; 3]));
}

/// The number of frames in a GIF.
fn gif_frames(path: &PathBuf) -> usize {
    use image::AnimationDecoder;
    let f = std::io::BufReader::new(std::fs::File::open(path).expect("open"));
    let dec = image::codecs::gif::GifDecoder::new(f).expect("a GIF");
    dec.into_frames().count()
}

/// Frame counts are capped (`--max-frames`, default 100): more is refused before any frame
/// is made, with the `--every` that fits; the cap can be raised or lifted.
#[test]
fn frame_counts_are_capped() {
    let file = rocket_qcs("frames-cap.qcs");
    let len = std::fs::metadata(&file).expect("len").len();
    let gif = scratch("frames-cap.gif");
    let dir = scratch("frames-cap");
    let start = std::time::Instant::now();
    let (c, err) = code(
        qcs()
            .arg("preview")
            .arg(&file)
            .arg(&gif)
            .args(["--every", "1"]),
    );
    assert_eq!(c, Some(2), "{err}");
    let every = len.div_ceil(100);
    assert!(
        err.contains(&format!("{len} frames would be made"))
            && err.contains(&format!("--every {every} or more")),
        "{err}"
    );
    assert!(start.elapsed().as_secs() < 10 && !gif.exists());
    let (c, err) = code(
        qcs()
            .arg("decode")
            .arg(&file)
            .arg("--frames")
            .arg(&dir)
            .args(["--every", "50"]),
    );
    assert_eq!(c, Some(2), "{err}");
    assert!(!dir.exists());
    // Within a raised cap: exactly ⌈len / every⌉ frames.
    let frames = len.div_ceil(1000);
    let ok = run(qcs().args(["-q", "preview"]).arg(&file).arg(&gif).args([
        "--every",
        "1000",
        "--max-frames",
        &frames.to_string(),
        "--size",
        "48",
    ]));
    assert!(ok.status.success(), "{ok:?}");
    assert_eq!(gif_frames(&gif) as u64, frames);
    let (c, _) = code(qcs().arg("preview").arg(&file).arg(&gif).args([
        "--every",
        "1000",
        "--max-frames",
        &(frames - 1).to_string(),
    ]));
    assert_eq!(c, Some(2));
    let ok = run(qcs()
        .args(["-q", "decode"])
        .arg(&file)
        .arg("--frames")
        .arg(&dir)
        .args(["--every", "500", "--max-frames", "none", "--size", "24"]));
    assert!(ok.status.success(), "{ok:?}");
    let n = std::fs::read_dir(&dir).expect("frames").count() as u64;
    assert_eq!(n, len.div_ceil(500));
}

/// `--recover` says what was damaged, where, and what it kept (even with `-q`), and draws
/// the verified levels before the damage; a file damaged in level 0 keeps nothing: an error.
#[test]
fn recovery_says_what_it_dropped() {
    // A file of levels only, whose level 3 is damaged.
    let file = scratch("recover.qcs");
    assert!(run(qcs()
        .args(["-q", "encode", "--levels-only", ROCKET])
        .arg(&file))
    .status
    .success());
    let bytes = std::fs::read(&file).expect("read");
    let ins = qcs::container::inspect(&bytes);
    let level = |k: u32| {
        ins.chunks
            .iter()
            .find(|c| c.level == Some(k))
            .expect("level")
    };
    let (l3, l4) = (
        level(3).chunk.offset as usize,
        level(4).chunk.offset as usize,
    );
    let mut damaged = bytes.clone();
    damaged[(l3 + l4) / 2] ^= 0x55;
    let bad = scratch("recover-bad.qcs");
    std::fs::write(&bad, &damaged).expect("write");
    let png = scratch("recover.png");
    let (c, err) = code(qcs().arg("decode").arg(&bad).arg(&png));
    assert_eq!(c, Some(3), "{err}");
    assert!(!png.exists());
    let (c, err) = code(
        qcs()
            .args(["-q", "decode", "--recover"])
            .arg(&bad)
            .arg(&png),
    );
    assert_eq!(c, Some(0), "{err}");
    let kept = ins.levels[2].samples.end;
    assert!(
        err.contains("is damaged")
            && err.contains(&format!("chunk #3 'L' at byte {l3}"))
            && err.contains(&format!(
                "kept what was verified before it: {kept} of 38400 samples"
            ))
            && err.contains("(3 of 10 levels)"),
        "{err}"
    );
    // The picture of the verified levels: that of the file cut where level 3 begins.
    let want = qcs::decode(
        &bytes,
        &qcs::DecodeOptions {
            max_bytes: Some(l3),
            thumbnail: true,
            ..Default::default()
        },
    )
    .expect("decode");
    assert_eq!(want.samples_used, kept);
    assert!(image::open(&png).expect("a PNG").to_rgb8() == want.image.to_rgb8());
    // Damage in level 0: nothing to keep.
    let mut first = bytes.clone();
    first[ins.header_len.expect("header") as usize + 4] ^= 0x55;
    std::fs::write(&bad, &first).expect("write");
    let (c, err) = code(qcs().args(["decode", "--recover"]).arg(&bad).arg(&png));
    assert_eq!(c, Some(3), "{err}");
    assert!(
        err.contains("damaged before anything could be kept"),
        "{err}"
    );
}

/// The smaller things a first hour meets: `--size` with one side keeps the aspect ratio;
/// `-q` keeps the warning that colours will look wrong; `encode DIR` recurses; `info`
/// applies the decoder's limits and calls them limits.
#[test]
fn sizes_warnings_folders_and_limits() {
    let file = rocket_qcs("small.qcs");
    for (size, want) in [
        ("240", (240, 160)),
        ("240x", (240, 160)),
        ("x80", (120, 80)),
    ] {
        let png = scratch(&format!("small-{size}.png"));
        let out = run(qcs()
            .args(["-q", "decode"])
            .arg(&file)
            .arg(&png)
            .args(["--size", size]));
        assert!(out.status.success(), "{out:?}");
        let img = image::open(&png).expect("a PNG");
        assert_eq!((img.width(), img.height()), want, "--size {size}");
    }
    // -q hides the summary, not the warning about wrong colours.
    let src = camera_png("small-camera.png", b"a wide-gamut profile");
    let cam = scratch("small-camera.qcs");
    assert!(run(qcs().args(["-q", "encode"]).arg(&src).arg(&cam))
        .status
        .success());
    let out = run(qcs()
        .args(["-q", "decode"])
        .arg(&cam)
        .arg(scratch("small-camera.bmp")));
    assert!(out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("warning: ") && err.contains("cannot hold the file's ICC"),
        "{err}"
    );
    assert_eq!(err.lines().count(), 1, "{err}");
    // A folder is searched recursively, its subfolders mirrored.
    let tree = scratch("small-tree");
    std::fs::create_dir_all(tree.join("sub/deeper")).expect("dirs");
    std::fs::copy(ROCKET, tree.join("top.png")).expect("copy");
    std::fs::copy(ROCKET, tree.join("sub/deeper/low.png")).expect("copy");
    std::fs::write(tree.join("sub/notes.txt"), "not an image").expect("write");
    let out_dir = scratch("small-tree-out");
    let out = run(qcs()
        .args(["-q", "encode"])
        .arg(&tree)
        .arg("--out-dir")
        .arg(&out_dir));
    assert!(out.status.success(), "{out:?}");
    let want = std::fs::read(&file).expect("read");
    assert_eq!(std::fs::read(out_dir.join("top.qcs")).expect("top"), want);
    assert_eq!(
        std::fs::read(out_dir.join("sub/deeper/low.qcs")).expect("low"),
        want
    );
    // The decoder's limits, in info too: a 40000-pixel-wide header is over the side limit.
    use qcs::container::{Coding, ContainerWriter, Header, Layout};
    let wide = Header::new(40000, 2, Layout::Grey, 100, 100, Coding::Raw { bits: 8 });
    let head = ContainerWriter::new(Vec::new(), &wide)
        .expect("header")
        .into_inner();
    let wide_file = scratch("small-wide.qcs");
    std::fs::write(&wide_file, head).expect("write");
    let (c, err) = code(qcs().arg("info").arg(&wide_file));
    assert_eq!(c, Some(4), "{err}");
    assert!(
        err.contains("exceeds the limits") && !err.contains("damaged"),
        "{err}"
    );
    let (c, err) = code(qcs().arg("decode").arg(&wide_file).arg(scratch("w.png")));
    assert_eq!(c, Some(4), "{err}");
    let (c, err) = code(qcs().args(["info", "--max-pixels", "none"]).arg(&wide_file));
    assert_eq!(c, Some(0), "{err}");
}

/// `qcs encode` says what it made: samples, levels, where the refinement begins, bytes, bits
/// per pixel (and per sample, of a file of levels only), and with `--psnr` the PSNR of the whole file; the limits and
/// `--threads` are flags.
#[test]
fn encode_says_what_it_made() {
    let out_file = scratch("made.qcs");
    let out = run(qcs().arg("encode").arg(ROCKET).arg(&out_file).arg("--psnr"));
    assert!(out.status.success(), "{out:?}");
    let err = String::from_utf8_lossy(&out.stderr);
    let bytes = std::fs::read(&out_file).expect("read");
    let d = qcs::decode(&bytes, &Default::default()).expect("decode");
    let reference = image::open(ROCKET).expect("png").to_rgb8();
    let psnr = qcs_lab::eval::psnr(&reference, &d.image.to_rgb8()).expect("psnr");
    let n = bytes.len();
    let at = qcs::container::inspect(&bytes)
        .refinement_offset
        .expect("a refinement");
    let want = [
        "480×320 Rgb, 64 samples in 1 level,".to_string(),
        format!(
            "levels in bytes 0..{at}, then a refinement of {} bytes",
            n as u64 - at
        ),
        format!(
            "{n} bytes (from {})",
            std::fs::metadata(ROCKET).expect("len").len()
        ),
        format!("{:.3} bits per pixel", n as f64 * 8.0 / (480.0 * 320.0)),
        format!("PSNR {psnr:.2} dB"),
    ];
    for w in &want {
        assert!(err.contains(w.as_str()), "{w:?} in {err}");
    }
    // Bits per sample only of a file of levels only (in a refinement's, 64 samples are a
    // sketch and the bits are the refinement's).
    assert!(!err.contains("per sample"), "{err}");
    // A lower sample limit caps the default density of a file of levels only, and says so.
    let out = run(qcs()
        .args(["encode", "--levels-only", "--max-samples", "5000"])
        .arg(ROCKET)
        .arg(&out_file));
    assert!(out.status.success(), "{out:?}");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("5000 samples, fewer than the 38400"), "{err}");
    let levels = std::fs::read(&out_file).expect("read");
    let h = qcs::container::inspect(&levels).header;
    assert_eq!(h.expect("header").total_samples, 5000);
    let per_sample = format!("{:.2} per sample", levels.len() as f64 * 8.0 / 5000.0);
    assert!(err.contains(&per_sample), "{per_sample} in {err}");
    // One thread draws the same picture.
    let (one, two) = (scratch("made-1.png"), scratch("made-2.png"));
    for (t, png) in [("1", &one), ("2", &two)] {
        let out = run(qcs()
            .args(["-q", "decode", "--threads", t])
            .arg(&out_file)
            .arg(png));
        assert!(out.status.success(), "{out:?}");
    }
    assert_eq!(
        std::fs::read(&one).expect("1"),
        std::fs::read(&two).expect("2")
    );
}

/// `qcs eval`'s PNG plots have their text (title, axis labels, ticks, legend), in the bundled
/// font: dark pixels where the title, the axes' descriptions and the legend are drawn.
#[test]
fn eval_png_plots_have_their_text() {
    let dir = scratch("eval-text");
    let seashore = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../tests/data/seashore-100x100.png"
    );
    let out = run(qcs()
        .args(["-q", "eval", "--quick", seashore, "--out"])
        .arg(&dir));
    assert!(out.status.success(), "{out:?}");
    let png = image::open(dir.join("curve-gouraud.png"))
        .expect("a PNG")
        .to_luma8();
    assert_eq!(png.dimensions(), (900, 560));
    let dark = |xs: std::ops::Range<u32>, ys: std::ops::Range<u32>| {
        ys.flat_map(|y| xs.clone().map(move |x| (x, y)))
            .filter(|&(x, y)| png.get_pixel(x, y).0[0] < 100)
            .count()
    };
    // The title, centred above the chart; "samples" under it; "PSNR (dB)" along the left.
    assert!(dark(200..700, 5..35) > 300, "no title");
    assert!(dark(400..500, 525..555) > 30, "no x description");
    assert!(dark(5..30, 200..360) > 30, "no y description");
    // Tick labels left of the y axis.
    assert!(dark(30..68, 40..500) > 200, "no y ticks");
}

/// `--max-memory`: a decode whose memory account is above it is refused (exit 4) before it
/// draws anything, and `encode` does not write a file that `decode` would refuse.
#[test]
fn a_memory_limit_refuses_decodes_and_encodes_beyond_it() {
    let file = rocket_qcs("memory.qcs");
    let png = scratch("memory.png");
    // 480 × 320 × 3 coefficients at 8 bytes: 3.5 MiB, more than 1 MiB.
    let (c, err) = code(
        qcs()
            .args(["--max-memory", "1M", "decode"])
            .arg(&file)
            .arg(&png),
    );
    assert_eq!(c, Some(4), "{err}");
    assert!(err.contains("exceeds the limit 1048576"), "{err}");
    assert!(!png.exists());
    let out = run(qcs()
        .args(["-q", "--max-memory", "8M", "decode"])
        .arg(&file)
        .arg(&png));
    assert!(out.status.success(), "{out:?}");
    let refused = scratch("memory-refused.qcs");
    let (c, err) = code(
        qcs()
            .args(["--max-memory", "1M", "encode"])
            .arg(ROCKET)
            .arg(&refused),
    );
    assert_eq!(c, Some(4), "{err}");
    assert!(err.contains("raise --max-memory"), "{err}");
    assert!(!refused.exists());
}

/// A netpbm output is the kind its name says, as viewers expect: `.ppm` a binary PPM (P6),
/// `.pgm` a binary PGM (P5), `.pnm` the one that holds the picture, `.pam` a PAM (P7); the
/// pictures are the PNG's. A `.pbm` (black and white) is refused before the work.
#[test]
fn netpbm_outputs_are_what_their_names_say() {
    let file = rocket_qcs("netpbm.qcs");
    let png = scratch("netpbm.png");
    assert!(run(qcs().args(["-q", "decode"]).arg(&file).arg(&png))
        .status
        .success());
    let want = image::open(&png).expect("the PNG");
    for (name, magic) in [
        ("n.ppm", "P6"),
        ("n.pgm", "P5"),
        ("n.pnm", "P6"),
        ("n.pam", "P7"),
    ] {
        let out = scratch(name);
        let dec = run(qcs().args(["-q", "decode"]).arg(&file).arg(&out));
        assert!(dec.status.success(), "{name}: {dec:?}");
        let bytes = std::fs::read(&out).expect("written");
        assert_eq!(&bytes[..2], magic.as_bytes(), "{name}");
        let got = image::load_from_memory(&bytes).expect("a netpbm file");
        if magic == "P5" {
            assert_eq!(got.to_luma8(), want.to_luma8(), "{name}");
        } else {
            assert_eq!(got.to_rgb8(), want.to_rgb8(), "{name}");
        }
    }
    let pbm = scratch("n.pbm");
    let (c, err) = code(qcs().args(["decode"]).arg(&file).arg(&pbm));
    assert_eq!(c, Some(2), "{err}");
    assert!(err.contains("a PBM holds black and white only"), "{err}");
    assert!(!pbm.exists());
}

/// An input deeper than 8 bits per channel is stored as 8 bits, and `qcs encode` says so
/// (even `--lossless` keeps only those 8 bits); an 8-bit input gets no such warning.
#[test]
fn a_deeper_input_is_said_to_be_stored_as_8_bits() {
    let deep = scratch("deep.png");
    let grey =
        image::ImageBuffer::from_fn(24, 16, |x, y| image::Luma([(x * 2731 + y * 97) as u16]));
    image::DynamicImage::ImageLuma16(grey)
        .save(&deep)
        .expect("a 16-bit PNG");
    let out = scratch("deep.qcs");
    let (c, err) = code(qcs().args(["encode", "--lossless"]).arg(&deep).arg(&out));
    assert_eq!(c, Some(0), "{err}");
    assert!(err.contains("16 bits per channel, stored as 8"), "{err}");
    let (c, err) = code(qcs().args(["encode"]).arg(ROCKET).arg(scratch("eight.qcs")));
    assert_eq!(c, Some(0), "{err}");
    assert!(!err.contains("bits per channel"), "{err}");
}

/// A photo format qcs does not read (a phone's HEIC) is named, with how to convert it, both
/// given alone and found in a folder (where the others still encode).
#[test]
fn an_unreadable_photo_format_says_how_to_convert_it() {
    let heic = scratch("IMG_0001.HEIC");
    std::fs::write(&heic, b"\0\0\0\x18ftypheic\0\0\0\0mif1heic").expect("write");
    let (c, err) = code(qcs().args(["encode"]).arg(&heic).arg(scratch("heic.qcs")));
    assert_eq!(c, Some(3), "{err}");
    assert!(
        err.contains("a HEIF/HEIC photo, which qcs does not read"),
        "{err}"
    );
    assert!(err.contains("heif-convert"), "{err}");
    let dir = scratch("phone");
    std::fs::create_dir_all(&dir).expect("dir");
    std::fs::copy(&heic, dir.join("IMG_0002.heic")).expect("copy");
    std::fs::copy(ROCKET, dir.join("rocket.png")).expect("copy");
    let out = scratch("phone-out");
    let (c, err) = code(qcs().args(["encode"]).arg(&dir).arg("--out-dir").arg(&out));
    assert_eq!(c, Some(3), "{err}");
    assert!(err.contains("1 of 2 files encoded"), "{err}");
    assert!(err.contains("IMG_0002.heic: cannot read image"), "{err}");
    assert!(out.join("rocket.qcs").exists());
}

/// Every format qcs writes it reads back as an input, TGA too (which has no signature: its
/// extension names it), and a lossless round trip through it keeps the picture.
#[test]
fn every_written_format_reads_back() {
    let file = rocket_qcs("formats.qcs");
    let png = scratch("formats.png");
    assert!(run(qcs().args(["-q", "decode"]).arg(&file).arg(&png))
        .status
        .success());
    let want = image::open(&png).expect("the PNG").to_rgb8();
    for ext in [
        "png", "gif", "bmp", "tiff", "webp", "ppm", "pam", "qoi", "tga",
    ] {
        let out = scratch(&format!("formats-out.{ext}"));
        let back = scratch(&format!("formats-{ext}.qcs"));
        let again = scratch(&format!("formats-{ext}.png"));
        let dec = run(qcs().args(["-q", "decode"]).arg(&file).arg(&out));
        assert!(dec.status.success(), "{ext}: {dec:?}");
        let enc = run(qcs()
            .args(["-q", "encode", "--lossless"])
            .arg(&out)
            .arg(&back));
        assert!(enc.status.success(), "{ext}: {enc:?}");
        let dec = run(qcs().args(["-q", "decode"]).arg(&back).arg(&again));
        assert!(dec.status.success(), "{ext}: {dec:?}");
        let got = image::open(&again).expect("the PNG").to_rgb8();
        // GIF's palette and WebP's lossy coding change the pixels; the others keep them.
        if !["gif", "webp"].contains(&ext) {
            assert_eq!(got, want, "{ext}");
        }
    }
}

/// An animated GIF is stored as its first frame, and `qcs encode` says so (given as a file or
/// piped); a GIF of one frame gets no such warning.
#[test]
fn an_animation_is_said_to_be_stored_as_its_first_frame() {
    let frame = |v: u8| {
        let rgba = image::RgbaImage::from_fn(24, 16, |x, y| {
            image::Rgba([v, x as u8 * 9, y as u8 * 13, 255])
        });
        image::Frame::new(rgba)
    };
    let gif = |name: &str, frames: Vec<image::Frame>| {
        let path = scratch(name);
        let mut bytes = Vec::new();
        image::codecs::gif::GifEncoder::new(&mut bytes)
            .encode_frames(frames)
            .expect("a GIF");
        std::fs::write(&path, bytes).expect("write");
        path
    };
    let anim = gif("anim.gif", vec![frame(10), frame(200), frame(90)]);
    let still = gif("still.gif", vec![frame(10)]);
    let says = "an animation; qcs stores its first frame";
    let (c, err) = code(qcs().args(["encode"]).arg(&anim).arg(scratch("anim.qcs")));
    assert_eq!(c, Some(0), "{err}");
    assert!(err.contains(says), "{err}");
    let piped = piped(
        qcs().args(["encode", "-"]).arg(scratch("anim-pipe.qcs")),
        &std::fs::read(&anim).expect("read"),
    );
    assert!(
        String::from_utf8_lossy(&piped.stderr).contains(says),
        "{piped:?}"
    );
    let (c, err) = code(qcs().args(["encode"]).arg(&still).arg(scratch("still.qcs")));
    assert_eq!(c, Some(0), "{err}");
    assert!(!err.contains("animation"), "{err}");
}

/// A mosaic runs off the image's edges, its tiles cut by the frame (the samples are
/// triangulated with their mirror images, as a decode does): along every edge, grout between
/// tiles, where a fill beyond the samples' hull drew a band of stripes without any.
#[test]
fn a_mosaic_runs_off_every_edge() {
    let file = rocket_qcs("mosaic.qcs");
    let png = scratch("mosaic.png");
    let out = run(qcs().args(["-q", "render"]).arg(&file).arg(&png));
    assert!(out.status.success(), "{out:?}");
    let img = image::open(&png).expect("the PNG").to_rgb8();
    let (w, h) = img.dimensions();
    let grout = |xs: std::ops::Range<u32>, ys: std::ops::Range<u32>| {
        let n = xs.len() * ys.len();
        let ink = ys
            .flat_map(|y| xs.clone().map(move |x| (x, y)))
            .filter(|&(x, y)| img.get_pixel(x, y).0 == qcs_lab::styles::INK)
            .count();
        ink as f64 / n as f64
    };
    for (edge, share) in [
        ("top", grout(0..w, 0..4)),
        ("bottom", grout(0..w, h - 4..h)),
        ("left", grout(0..4, 0..h)),
        ("right", grout(w - 4..w, 0..h)),
    ] {
        assert!((0.25..0.75).contains(&share), "{edge}: {share:.3} of grout");
    }
}

/// A picture with transparency written where it cannot be held (JPEG, PPM) is said to lose
/// it; PNG keeps it, and an opaque picture loses nothing to say.
#[test]
fn lost_transparency_is_said() {
    let rgb = image::open(ROCKET).expect("rocket").to_rgb8();
    let with_alpha = |a: u8| {
        let img = image::RgbaImage::from_fn(rgb.width(), rgb.height(), |x, y| {
            let [r, g, b] = rgb.get_pixel(x, y).0;
            image::Rgba([r, g, b, if x < 100 { a } else { 255 }])
        });
        let png = scratch(&format!("alpha-{a}.png"));
        img.save(&png).expect("an RGBA PNG");
        let file = scratch(&format!("alpha-{a}.qcs"));
        assert!(run(qcs().args(["-q", "encode"]).arg(&png).arg(&file))
            .status
            .success());
        file
    };
    let says = "cannot hold the picture's transparency";
    let (clear, opaque) = (with_alpha(0), with_alpha(255));
    for (file, out, warned) in [
        (&clear, "alpha-0.jpg", true),
        (&clear, "alpha-0.ppm", true),
        (&clear, "alpha-0-out.png", false),
        (&opaque, "alpha-255.jpg", false),
    ] {
        let (c, err) = code(qcs().args(["-q", "decode"]).arg(file).arg(scratch(out)));
        assert_eq!(c, Some(0), "{out}: {err}");
        assert_eq!(err.contains(says), warned, "{out}: {err}");
    }
}
