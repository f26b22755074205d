//! The plots of real runs rendered with resvg, as a reader sees them: every text element (title,
//! tick labels, axis titles, legend) lies on the canvas and no two overlap. usvg lays the text
//! out with the machine's fonts (fontconfig's; DejaVu on ours), which gives each text's box.
//!
//! To look at the PNGs, set `IMPULSE_PLOTS_PNG=DIR`: they are copied there.

mod common;

use common::fixture;
use resvg::{tiny_skia, usvg};

/// Two text boxes that overlap by at most this much (pixels) in either direction touch rather
/// than overlap (glyph outlines are antialiased across pixel edges).
const OVERLAP_TOLERANCE_PX: f32 = 0.5;
/// A text box may reach this far (pixels) past the canvas's edge (antialiasing again).
const EDGE_TOLERANCE_PX: f32 = 0.5;

/// The options with the machine's fonts; "sans-serif" is the first sans family found.
fn options() -> usvg::Options<'static> {
    let mut opt = usvg::Options::default();
    let db = opt.fontdb_mut();
    db.load_system_fonts();
    assert!(
        !db.is_empty(),
        "no fonts found: install one (Debian: fonts-dejavu-core) for the text layout"
    );
    let sans = db
        .faces()
        .flat_map(|f| f.families.iter().map(|(name, _)| name.clone()))
        .find(|name| name == "DejaVu Sans")
        .or_else(|| db.faces().next().map(|f| f.families[0].0.clone()));
    if let Some(sans) = sans {
        db.set_sans_serif_family(sans);
    }
    opt
}

/// The laid-out boxes of every text of `tree`: (the text, [x0, y0, x1, y1] on the canvas).
fn text_boxes(group: &usvg::Group, out: &mut Vec<(String, [f32; 4])>) {
    for node in group.children() {
        match node {
            usvg::Node::Group(g) => text_boxes(g, out),
            usvg::Node::Text(t) => {
                let b = t.abs_bounding_box();
                let text: String = t.chunks().iter().map(|c| c.text()).collect();
                out.push((text, [b.left(), b.top(), b.right(), b.bottom()]));
            }
            _ => {}
        }
    }
}

/// What is wrong with the text of the SVG `svg`: texts off the canvas, texts overlapping.
/// Also renders it to `png`.
fn text_faults(svg: &str, png: &std::path::Path) -> Vec<String> {
    let tree = usvg::Tree::from_str(svg, &options()).unwrap();
    let (w, h) = (tree.size().width(), tree.size().height());
    let mut boxes = Vec::new();
    text_boxes(tree.root(), &mut boxes);
    // Every <text> was laid out (usvg drops a text no font can show).
    assert_eq!(
        boxes.len(),
        svg.matches("<text").count(),
        "texts not laid out"
    );
    assert!(boxes.len() >= 10, "a plot with {} texts", boxes.len());
    let mut faults = Vec::new();
    let e = EDGE_TOLERANCE_PX;
    for (text, b) in &boxes {
        if b[0] < -e || b[1] < -e || b[2] > w + e || b[3] > h + e {
            faults.push(format!(
                "{text:?} leaves the {w} × {h} canvas: x {:.1}..{:.1}, y {:.1}..{:.1}",
                b[0], b[2], b[1], b[3]
            ));
        }
    }
    let t = OVERLAP_TOLERANCE_PX;
    for (i, (ta, a)) in boxes.iter().enumerate() {
        for (tb, b) in &boxes[i + 1..] {
            let dx = a[2].min(b[2]) - a[0].max(b[0]);
            let dy = a[3].min(b[3]) - a[1].max(b[1]);
            if dx > t && dy > t {
                faults.push(format!("{ta:?} and {tb:?} overlap by {dx:.1} × {dy:.1} px"));
            }
        }
    }
    let mut pixmap = tiny_skia::Pixmap::new(w.ceil() as u32, h.ceil() as u32).unwrap();
    resvg::render(&tree, tiny_skia::Transform::default(), &mut pixmap.as_mut());
    pixmap.save_png(png).unwrap();
    if let Some(dir) = std::env::var_os("IMPULSE_PLOTS_PNG") {
        std::fs::copy(
            png,
            std::path::Path::new(&dir).join(png.file_name().unwrap()),
        )
        .unwrap();
    }
    faults
}

/// Checks the SVG files `names` in `dir`.
fn check(dir: &std::path::Path, names: &[&str]) {
    let mut faults = Vec::new();
    for name in names {
        let path = dir.join(name);
        let svg = std::fs::read_to_string(&path).unwrap();
        for f in text_faults(&svg, &path.with_extension("png")) {
            faults.push(format!("{name}: {f}"));
        }
    }
    assert!(faults.is_empty(), "{}", faults.join("\n"));
}

#[test]
fn the_run_plots_text_stays_on_the_canvas_without_overlaps() {
    let dir = common::Scratch::new("plots-run");
    let (ok, _, err) = common::impulse_text(&[
        "run",
        &fixture("scenes/dominos.ron"),
        "--until",
        "1",
        "--plot",
        dir.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    check(&dir, &["energy.svg", "paths.svg"]);
}

#[test]
fn the_reduce_plot_text_stays_on_the_canvas_without_overlaps() {
    let dir = common::Scratch::new("plots-reduce");
    let (ok, _, err) = common::impulse_text(&[
        "reduce",
        &fixture("mechanisms/y.ron"),
        "--load",
        "a3:100,0,0",
        "--until",
        "0.5",
        "--plot",
        dir.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    check(&dir, &["error.svg"]);
}
