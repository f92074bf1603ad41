//! Reference PNGs (issue 5; style principle 12): small inputs under
//! `tests/fixtures/render/<case>/` are drawn by the real binary and compared
//! pixel by pixel with the `expected.png` beside them. A failure writes a
//! three-panel diff image to `<target>/render-diffs/<case>.png`;
//! `UPDATE_REFS=1` rewrites the references instead. `tests/README.md` says what
//! each case checks and how to review new references.

use std::path::{Path, PathBuf};

use resvg::tiny_skia::{Pixmap, PremultipliedColorU8};

use crate::support;

/// A channel may differ by this much without the pixel counting as different:
/// anti-aliasing and float rounding in the rasteriser vary by a unit or two
/// between CPUs and compilers (resvg's own suite allows 1).
const CHANNEL_TOLERANCE: u8 = 2;
/// Share of pixels that may differ before the case fails: 0.01 %, 16 pixels
/// of a 400 × 400 picture, room for a few edge pixels to round differently.
/// SVG coordinates have two fixed decimals, so float noise in the layout
/// rarely reaches the pixels at all, while real changes are larger: moving
/// the tabs under the labels changed 32 pixels of `neighbours`.
const MAX_DIFFERING_SHARE: f64 = 0.0001;

/// Every picture is this many canvas units (= pixels) square: small enough to
/// keep the references a few tens of kilobytes, large enough for labels.
const SIDE: &str = "400";

fn fixture(case: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/render")
        .join(case)
}

/// Renders `tests/fixtures/render/<case>/input.json` with `nptreemap layout`
/// and the given extra options, then compares it with (or, with
/// `UPDATE_REFS=1`, writes) the reference `expected.png`.
fn check(case: &str, options: &[&str]) {
    let dir = support::temp_dir(&format!("render_refs_{case}"));
    let actual_path = dir.join(format!("{case}.png"));
    let mut args = vec!["--width", SIDE, "--height", SIDE, "--seed", "1"];
    args.extend_from_slice(options);
    support::layout(&fixture(case).join("input.json"), &[&actual_path], &args);
    let actual_bytes = std::fs::read(&actual_path).expect("the PNG was written");
    let reference = fixture(case).join("expected.png");

    if std::env::var_os("UPDATE_REFS").is_some_and(|v| v == "1") {
        std::fs::write(&reference, &actual_bytes).expect("write the reference");
        eprintln!(
            "{case}: wrote {}; review it by eye before committing",
            reference.display()
        );
        return;
    }

    let actual = Pixmap::decode_png(&actual_bytes).expect("the binary wrote a valid PNG");
    let Ok(expected) = Pixmap::load_png(&reference) else {
        panic!(
            "{case}: no readable reference at {}; make it with \
             `UPDATE_REFS=1 cargo test --workspace render_refs` and review it",
            reference.display()
        );
    };
    assert_eq!(
        (actual.width(), actual.height()),
        (expected.width(), expected.height()),
        "{case}: picture size differs from {}",
        reference.display()
    );
    let differing: Vec<bool> = expected
        .pixels()
        .iter()
        .zip(actual.pixels())
        .map(|(e, a)| differs(*e, *a))
        .collect();
    let count = differing.iter().filter(|d| **d).count();
    let allowed = (MAX_DIFFERING_SHARE * differing.len() as f64) as usize;
    if count > allowed {
        let diff = write_diff(case, &expected, &actual, &differing);
        panic!(
            "{case}: {count} pixels differ from {} by more than {CHANNEL_TOLERANCE} \
             (at most {allowed} may); expected | actual | difference in {}. If the \
             change is intended, regenerate with `UPDATE_REFS=1 cargo test --workspace \
             render_refs` and review the new picture",
            reference.display(),
            diff.display()
        );
    }
}

/// Whether any channel of the two pixels differs by more than the tolerance.
fn differs(e: PremultipliedColorU8, a: PremultipliedColorU8) -> bool {
    [
        (e.red(), a.red()),
        (e.green(), a.green()),
        (e.blue(), a.blue()),
        (e.alpha(), a.alpha()),
    ]
    .iter()
    .any(|(x, y)| x.abs_diff(*y) > CHANNEL_TOLERANCE)
}

/// Writes `expected | actual | difference` side by side, the third panel the
/// expected picture faded to light grey with every differing pixel red, and
/// returns its path, `<target>/render-diffs/<case>.png`.
fn write_diff(case: &str, expected: &Pixmap, actual: &Pixmap, differing: &[bool]) -> PathBuf {
    let (w, h) = (expected.width() as usize, expected.height() as usize);
    let mut panel = Pixmap::new(3 * w as u32, h as u32).expect("diff image size");
    let red = PremultipliedColorU8::from_rgba(255, 0, 0, 255).expect("opaque red");
    let out = panel.pixels_mut();
    for y in 0..h {
        for x in 0..w {
            let k = y * w + x;
            let row = y * 3 * w;
            out[row + x] = expected.pixels()[k];
            out[row + w + x] = actual.pixels()[k];
            out[row + 2 * w + x] = if differing[k] {
                red
            } else {
                let p = expected.pixels()[k];
                // Luminance squeezed into 170..=255, so the picture stays
                // recognisable and red stands out.
                let luma = (30 * u32::from(p.red())
                    + 59 * u32::from(p.green())
                    + 11 * u32::from(p.blue()))
                    / 100;
                let light = (170 + luma / 3) as u8;
                PremultipliedColorU8::from_rgba(light, light, light, 255).expect("opaque grey")
            };
        }
    }
    // CARGO_TARGET_TMPDIR is `<target>/tmp`; the diffs go next to it.
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .parent()
        .expect("the tmp dir is inside the target dir")
        .join("render-diffs");
    std::fs::create_dir_all(&dir).expect("create render-diffs");
    let path = dir.join(format!("{case}.png"));
    panel.save_png(&path).expect("write the diff image");
    path
}

/// A plain hierarchy without similarity: group colours, white outlines thicker
/// between groups, one label per leaf.
#[test]
fn plain_hierarchy() {
    check("plain", &[]);
}

/// Neighbour lists (made-up borders; Europe's five countries are all pairwise
/// neighbours, which no planar layout realises): interlocking tabs on shared
/// edges and the red "unlinked" counts on cells with unrealised constraints.
#[test]
fn neighbor_tabs_and_unlinked_markers() {
    check("neighbours", &[]);
}

/// The circle outline: cells fill the inscribed circle, the corners stay
/// background.
#[test]
fn circle_outline() {
    check("circle", &["--outline", "circle"]);
}

/// Labels: accented Latin, Greek, Cyrillic and symbols drawn with the built-in
/// font, long labels shrunk to fit, one far too long label and one too small
/// cell left unlabelled.
#[test]
fn long_and_unicode_labels() {
    check("labels", &[]);
}

/// Four levels: outlines thinning per level (3, 1.5, 0.75, 0.5) and child
/// shades of each group's colour.
#[test]
fn deep_hierarchy() {
    check("deep", &[]);
}

/// Issue 32, item 1: the PNG is painted without usvg, in the picture's own
/// frame, and is the single pass resvg makes of the same SVG (with the
/// built-in font) within the references' tolerance, on every case. (The
/// references before it were painted in two strips, whose seam moved the
/// anti-aliasing of the edges crossing it.)
#[test]
fn the_pictures_are_resvgs_single_pass_of_their_svg() {
    use resvg::{tiny_skia, usvg};
    let font = Path::new(env!("CARGO_MANIFEST_DIR")).join("src/render/fonts/DejaVuSans.ttf");
    let mut db = usvg::fontdb::Database::new();
    db.load_font_data(std::fs::read(&font).expect("the built-in font"));
    db.set_sans_serif_family("DejaVu Sans");
    let options = usvg::Options {
        font_family: "DejaVu Sans".to_string(),
        fontdb: std::sync::Arc::new(db),
        ..usvg::Options::default()
    };
    for (case, extra) in [
        ("plain", &[][..]),
        ("neighbours", &[][..]),
        ("circle", &["--outline", "circle"][..]),
        ("labels", &[][..]),
        ("deep", &[][..]),
    ] {
        let dir = support::temp_dir(&format!("render_refs_pass_{case}"));
        let (png, svg) = (dir.join("p.png"), dir.join("p.svg"));
        let mut args = vec!["--width", SIDE, "--height", SIDE, "--seed", "1"];
        args.extend_from_slice(extra);
        support::layout(&fixture(case).join("input.json"), &[&png, &svg], &args);
        let ours = Pixmap::load_png(&png).expect("png");
        let tree = usvg::Tree::from_str(&std::fs::read_to_string(&svg).expect("svg"), &options)
            .expect("usvg parses the picture");
        let size = tree.size().to_int_size();
        let mut pass = Pixmap::new(size.width(), size.height()).expect("pixmap");
        resvg::render(&tree, tiny_skia::Transform::identity(), &mut pass.as_mut());
        let differing = ours
            .pixels()
            .iter()
            .zip(pass.pixels())
            .filter(|(a, b)| differs(**a, **b))
            .count();
        let allowed = (MAX_DIFFERING_SHARE * ours.pixels().len() as f64) as usize;
        assert!(
            differing <= allowed,
            "{case}: {differing} pixels differ from resvg's single pass by more than \
             {CHANNEL_TOLERANCE} (at most {allowed} may)"
        );
    }
}

/// Issue 32, item 1: a PNG made without usvg. The examples' pictures and a
/// real dataset's (tabs, markers, legend, labels, group names) are drawn
/// entirely by the PNG's own items: the PNG's stage line counts no usvg
/// document.
#[test]
fn the_pngs_of_real_pictures_use_no_usvg_document() {
    let real = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/real/debian-packages");
    let copy = support::temp_dir("render_refs_usvg_debian");
    for entry in std::fs::read_dir(&real).expect("the real dataset") {
        let path = entry.expect("entry").path();
        if path.is_file() {
            std::fs::copy(&path, copy.join(path.file_name().expect("name"))).expect("copy");
        }
    }
    let configs = [
        support::example("countries", "usvg_countries"),
        support::example("movies", "usvg_movies"),
        copy.join("nptreemap.yaml"),
    ];
    for config in configs {
        let out = support::bin()
            .args(["-v", "build"])
            .arg(&config)
            .output()
            .expect("run nptreemap");
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let log = String::from_utf8_lossy(&out.stderr);
        let pngs: Vec<&str> = log
            .lines()
            .filter(|l| l.contains("render ") && l.contains(".png ran"))
            .collect();
        assert!(
            !pngs.is_empty(),
            "{}: no PNG rendered:\n{log}",
            config.display()
        );
        for line in pngs {
            assert!(
                line.contains("usvg documents: 0") && line.contains("0 kept"),
                "{}: {line}",
                config.display()
            );
        }
    }
}
