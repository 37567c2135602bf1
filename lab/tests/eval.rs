//! The evaluation: metrics against hand-computed values, and `eval::run`
//! writing every file it promises on a small image.

use std::path::PathBuf;

use qcs::reconstruction::Method;
use qcs_lab::eval::{self, curve_counts, psnr_bytes, roughness, EvalOptions};
use qcs_lab::samplers;

fn tmp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("qcs-eval-test-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

#[test]
fn psnr_known_values() {
    // One byte off by 255 in 3 bytes: MSE = 255²/3 → PSNR = 10·log10(3).
    let p = psnr_bytes(&[0, 0, 0], &[255, 0, 0]).unwrap();
    assert!((p - 10.0 * 3f64.log10()).abs() < 1e-12);
    // Off by 16 everywhere: 20·log10(255/16).
    let a = vec![100u8; 300];
    let b = vec![116u8; 300];
    assert!((psnr_bytes(&a, &b).unwrap() - 20.0 * (255.0f64 / 16.0).log10()).abs() < 1e-12);
    assert_eq!(psnr_bytes(&a, &a).unwrap(), f64::INFINITY);
    assert!(psnr_bytes(&a, &b[..299]).is_err());
    assert!(psnr_bytes(&[], &[]).is_err());
}

#[test]
fn roughness_separates_staircase_from_smooth() {
    let x: Vec<f64> = curve_counts(256, 32768, 40)
        .iter()
        .map(|&n| n as f64)
        .collect();
    let smooth: Vec<f64> = x
        .iter()
        .map(|n| 10.0 + 1.35 * n.log2() - 0.01 * n.log2().powi(2))
        .collect();
    let stairs: Vec<f64> = x
        .iter()
        .map(|n| 10.0 + 1.35 * (n.log2() / 2.0).floor() * 2.0)
        .collect();
    let r_smooth = roughness(&x, &smooth).unwrap();
    let r_stairs = roughness(&x, &stairs).unwrap();
    assert!(r_smooth < 1e-9, "{r_smooth}");
    assert!(r_stairs > 0.3, "{r_stairs}");
    assert_eq!(roughness(&x[..3], &smooth[..3]), None);
}

#[test]
fn curve_counts_include_squares_and_are_dense() {
    let c = curve_counts(256, 32768, 40);
    assert!(c.windows(2).all(|w| w[0] < w[1]));
    for sq in [289, 1089, 4225, 16641] {
        assert!(c.contains(&sq));
    }
    assert!((43..=44).contains(&c.len()), "{}", c.len());
    // Log-spaced: consecutive ratio ≤ 2^(7/39) + rounding.
    assert!(c.windows(2).all(|w| (w[1] as f64 / w[0] as f64) < 1.14));
}

#[test]
fn run_writes_every_promised_file() {
    let img = image::open(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../tests/data/seashore-100x100.png"
    ))
    .unwrap()
    .to_rgb8();
    let small = image::imageops::resize(&img, 40, 30, image::imageops::FilterType::Triangle);
    let images = vec![
        ("seashore".to_string(), img.clone()),
        ("small".to_string(), small),
    ];
    let samplers = samplers::all(0);
    let options = EvalOptions {
        table_counts: vec![81, 289],
        curve_counts: curve_counts(64, 400, 6),
        methods: vec![Method::Gouraud, Method::Shepard],
        panel_count: 100,
        panel_size: 64,
        spectrum_size: 32,
    };
    let dir = tmp_dir("run");
    let mut calls = Vec::new();
    let report = eval::run(&images, &samplers, &dir, &options, &mut |p| {
        calls.push((p.done, p.total, p.stage.to_string()))
    })
    .unwrap();

    // Progress: one call per (image, sampler, method) and per sampler's panels, in order.
    let total = 2 * 5 * 2 + 5;
    assert_eq!(calls.len(), total);
    assert!(calls
        .iter()
        .enumerate()
        .all(|(k, c)| c.0 == k + 1 && c.1 == total));
    assert_eq!(calls[0].2, "seashore/periodic/gouraud");

    // Every measurement is there.
    let mut counts: Vec<usize> = options
        .table_counts
        .iter()
        .chain(&options.curve_counts)
        .copied()
        .collect();
    counts.sort_unstable();
    counts.dedup();
    assert_eq!(report.rows.len(), 2 * 5 * 2 * counts.len());
    assert!(report
        .rows
        .iter()
        .all(|r| r.psnr.is_finite() && r.psnr > 5.0 && r.psnr < 60.0));

    // An independent PSNR for one row: reconstruct from the periodic 9×9 grid and compare.
    let sites = qcs_lab::samplers::Sampler::sites(&samplers::Periodic, 100, 100, 81);
    let colours = eval::sample_colours(&img, &sites);
    let rec =
        qcs::reconstruction::render((100, 100), 3, &sites, &colours, Method::Shepard, 100, 100);
    let want = psnr_bytes(img.as_raw(), &rec).unwrap();
    let row = report
        .rows
        .iter()
        .find(|r| {
            r.image == "seashore"
                && r.sampler == "periodic"
                && r.method == Method::Shepard
                && r.count == 81
        })
        .unwrap();
    assert!((row.psnr - want).abs() < 1e-12);

    // Files.
    let mut want_files = vec![
        "psnr.csv",
        "mean.csv",
        "table.csv",
        "claims.csv",
        "index.html",
    ]
    .into_iter()
    .map(String::from)
    .collect::<Vec<_>>();
    for m in ["gouraud", "shepard"] {
        want_files.push(format!("curve-{m}.svg"));
        want_files.push(format!("curve-{m}.png"));
    }
    for s in ["periodic", "farthest", "jittered", "halton", "random"] {
        for kind in ["sites", "mosaic", "voronoi", "spectrum"] {
            want_files.push(format!("{s}-{kind}.png"));
        }
    }
    for f in &want_files {
        let path = dir.join(f);
        let len = std::fs::metadata(&path).map(|m| m.len()).unwrap_or(0);
        assert!(len > 0, "{f} missing or empty");
        assert!(report.files.contains(&path), "{f} not listed in the report");
    }
    assert_eq!(report.files.len(), want_files.len());
    for f in &want_files {
        if f.ends_with(".png") {
            image::open(dir.join(f)).unwrap_or_else(|e| panic!("{f}: {e}"));
        }
    }
    let (pw, ph) = image::image_dimensions(dir.join("halton-mosaic.png")).unwrap();
    assert_eq!((pw, ph), (64, 64));
    assert_eq!(
        image::image_dimensions(dir.join("halton-spectrum.png")).unwrap(),
        (32, 32)
    );

    // CSV and HTML contents.
    let psnr_csv = std::fs::read_to_string(dir.join("psnr.csv")).unwrap();
    assert_eq!(psnr_csv.lines().count(), report.rows.len() + 1);
    let table = std::fs::read_to_string(dir.join("table.csv")).unwrap();
    assert_eq!(
        table.lines().next().unwrap(),
        "method,samples,periodic,farthest,jittered,halton,random"
    );
    assert_eq!(table.lines().count(), 1 + 2 * 2);
    let html = std::fs::read_to_string(dir.join("index.html")).unwrap();
    for f in want_files.iter().filter(|f| f.as_str() != "index.html") {
        assert!(
            html.contains(&format!("\"{f}\"")),
            "index.html does not link {f}"
        );
    }
    assert!(html.contains("</html>"));

    // Claims: five, the quasicrystal ones not checkable without that sampler.
    assert_eq!(report.claims.len(), 5);
    assert_eq!(report.claims[3].holds, None);
    assert_eq!(report.claims[4].holds, None);
    assert!(report.claims[1].holds.is_some(), "{:?}", report.claims[1]);

    // Mean is the mean of the two images.
    let m = report.mean("random", Method::Gouraud, 289).unwrap();
    let rows: Vec<f64> = report
        .rows
        .iter()
        .filter(|r| r.sampler == "random" && r.method == Method::Gouraud && r.count == 289)
        .map(|r| r.psnr)
        .collect();
    assert_eq!(rows.len(), 2);
    assert!((m - (rows[0] + rows[1]) / 2.0).abs() < 1e-12);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn run_rejects_bad_input() {
    let dir = tmp_dir("bad");
    let img = image::RgbImage::new(8, 8);
    let s = samplers::all(0);
    assert!(eval::run(&[], &s, &dir, &EvalOptions::default(), &mut |_| {}).is_err());
    assert!(eval::run(
        &[("a".into(), img.clone())],
        &[],
        &dir,
        &EvalOptions::default(),
        &mut |_| {}
    )
    .is_err());
    let bad = EvalOptions {
        spectrum_size: 1,
        ..EvalOptions::default()
    };
    assert!(eval::run(&[("a".into(), img)], &s, &dir, &bad, &mut |_| {}).is_err());
    let _ = std::fs::remove_dir_all(&dir);
}
