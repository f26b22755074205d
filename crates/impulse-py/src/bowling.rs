//! The bowling study (thesis §7.4, Fig. 7.10): straight and hooking throws run in shards,
//! shards merged with the library's merge, the pins felled per bin of pin-line crossings read
//! back as arrays. A shard's result is the text of the file `impulse bowling … --shard K/N
//! --out FILE` writes, byte for byte, so a study split over machines by Python
//! (`impulse.distributed`) or by the CLI merges the same way.

use std::path::PathBuf;

use impulse_sim::batch::Shard;
use impulse_sim::bowling::{
    self, AlleyDesc, BIN_WIDTH, BowlingFile, Mean, ThrowOutcome, ThrowSettings,
};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::error;
use crate::study_file::{Kept, Outcomes, merge_texts, run_kept, study_text};

/// A study file's text read back and checked (its alley, settings and size), as `impulse
/// bowling merge` and `--from` read a file; `k` names it in the error.
fn read_study(text: &str, k: usize) -> Result<BowlingFile, String> {
    let file: BowlingFile = serde_json::from_str(text)
        .map_err(|e| format!("studies[{k}]: not a bowling study file: {e}"))?;
    file.check().map_err(|e| format!("studies[{k}]: {e}"))?;
    Ok(file)
}

/// The alley of `path` (a RON file, `Alley(…)`), or the default USBC alley.
fn read_alley(path: Option<&PathBuf>) -> Result<AlleyDesc, String> {
    match path {
        Some(path) => {
            let text = std::fs::read_to_string(path)
                .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
            AlleyDesc::from_ron(&text, &path.display().to_string()).map_err(|e| e.to_string())
        }
        None => Ok(AlleyDesc::default()),
    }
}

/// The study's settings from the CLI's options (`ThrowSettings::validate` checks them).
fn throw_settings(
    speed: f64,
    spin: f64,
    angle: f64,
    center: f64,
    width: f64,
    settle: f64,
) -> ThrowSettings {
    ThrowSettings {
        speed,
        hook_spin: spin,
        hook_angle_degrees: angle,
        window_center: center,
        window_width: width,
        settle_time: settle,
    }
}

/// Runs the throws of one shard of a bowling study (thesis §7.4) with the GIL released;
/// returns the text of the study file, byte for byte what `impulse bowling --throws THROWS
/// --seed SEED --shard K/N --out FILE` writes (with `shard=(0, 1)`, the whole study). The
/// keywords are the CLI's options with its defaults: `throws` of each kind (straight and
/// hook; the thesis threw 320), release `speed` (m/s), a hook's `spin` (rad/s) and release
/// `angle` (degrees right of straight), the window of pin-line crossings aimed at (`center`,
/// `width`, m), the longest run after the crossing (`settle`, simulated s), and `alley`, an
/// `Alley(…)` RON file (default: the USBC alley `impulse bowling --print-alley` prints).
/// `threads` (default: every core) does not change the result.
///
/// With `out`, the study is kept as the CLI keeps it: each finished throw in the journal
/// `OUT.partial`, and the file written to `out` when the shard is done. A call stopped before
/// that (by `max_wall` seconds of wall-clock time, after which no throw starts, or by a kill)
/// and made again with the same arguments runs only the throws the journal does not hold —
/// and so does `impulse bowling … --out OUT`, which reads the same journal, and the other way
/// round. A call stopped by `max_wall` raises `ImpulseError` saying how many throws it kept.
/// A call whose `out` already holds this shard's finished file (and no journal) returns that
/// file without throwing again (a Dask study re-run after a kill, `impulse.distributed`).
/// Raises `ImpulseError` for a bad shard, setting, throw count or alley file, or a journal of
/// another study at `OUT.partial`.
#[pyfunction]
#[pyo3(signature = (throws=320, seed=1, shard=(0, 1), threads=None, alley=None, speed=8.0,
                    spin=12.0, angle=2.0, center=0.0, width=0.40, settle=4.0, out=None,
                    max_wall=None))]
#[allow(clippy::too_many_arguments)] // the CLI's options as Python keywords
fn run_bowling_shard(
    py: Python<'_>,
    throws: u64,
    seed: u64,
    shard: (u64, u64),
    threads: Option<usize>,
    alley: Option<PathBuf>,
    speed: f64,
    spin: f64,
    angle: f64,
    center: f64,
    width: f64,
    settle: f64,
    out: Option<PathBuf>,
    max_wall: Option<f64>,
) -> PyResult<String> {
    let shard: Shard = format!("{}/{}", shard.0, shard.1).parse().map_err(error)?;
    let settings = throw_settings(speed, spin, angle, center, width, settle);
    if let Some(w) = max_wall
        && !(w.is_finite() && w > 0.0)
    {
        return Err(error(format!(
            "max_wall {w}: must be a positive number of seconds"
        )));
    }
    let threads =
        threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    py.detach(|| {
        let alley = read_alley(alley.as_ref())?;
        settings.validate().map_err(|e| e.to_string())?;
        let total = throws
            .checked_mul(2)
            .ok_or_else(|| format!("throws = {throws}: too many"))?;
        let run_alley = alley.clone();
        let file = BowlingFile {
            alley,
            settings,
            seed,
            throws_per_kind: throws,
            outcomes: Vec::new(),
        };
        let study = Kept {
            command: "impulse bowling",
            runs: "throws",
            shard,
            total,
            out: out.as_deref(),
            max_wall,
        };
        let outcomes = Outcomes {
            of: |f: &mut BowlingFile| &mut f.outcomes,
            index: |t: &ThrowOutcome| t.index,
        };
        let file = run_kept(&study, file, &outcomes, |hooks| {
            bowling::run_throws_with(&run_alley, &settings, seed, throws, shard, threads, hooks)
                .map_err(|e| e.to_string())
        })?;
        study_text(&file)
    })
    .map_err(error)
}

/// The scene (RON) of throw `index` of a bowling study, the text `impulse bowling --scene
/// INDEX` prints (its standard output, final newline included: saved to a file, `impulse run`
/// or `World.from_scene` replays that throw exactly). The study's keywords as
/// `run_bowling_shard` takes them. Raises `ImpulseError` for a throw outside the study (0 to
/// 2·throws − 1), a bad setting or alley file.
#[pyfunction]
#[pyo3(signature = (index, throws=320, seed=1, alley=None, speed=8.0, spin=12.0, angle=2.0,
                    center=0.0, width=0.40, settle=4.0))]
#[allow(clippy::too_many_arguments)] // the CLI's options as Python keywords
fn bowling_throw_scene(
    py: Python<'_>,
    index: u64,
    throws: u64,
    seed: u64,
    alley: Option<PathBuf>,
    speed: f64,
    spin: f64,
    angle: f64,
    center: f64,
    width: f64,
    settle: f64,
) -> PyResult<String> {
    let settings = throw_settings(speed, spin, angle, center, width, settle);
    py.detach(|| {
        let alley = read_alley(alley.as_ref())?;
        settings.validate().map_err(|e| e.to_string())?;
        let desc = bowling::throw_scene(&alley, &settings, seed, throws, index)
            .map_err(|e| e.to_string())?;
        let text = desc.to_ron().map_err(|e| e.to_string())?;
        Ok(format!(
            "// Throw {index} of a bowling study (seed {seed}, {throws} throws of each kind): \
             `impulse run` on this file replays it.\n{text}\n"
        ))
    })
    .map_err(|e: String| error(e))
}

/// Merges the shard files of one bowling study (their texts, as `run_bowling_shard` returns
/// or `impulse bowling --out` writes) with the library's merge; returns the text of the
/// whole study's file, byte for byte what `impulse bowling merge … --out FILE` writes.
/// Raises `ImpulseError` for files of different studies or a throw held twice.
#[pyfunction]
fn merge_bowling_studies(py: Python<'_>, studies: Vec<String>) -> PyResult<String> {
    py.detach(|| merge_texts(&studies, read_study, bowling::merge))
        .map_err(error)
}

/// A band's figures, one value per kind: `mean` (NaN without throws), `se` (NaN below two
/// throws), `n`, each shape (2,), straight then hook.
fn band_dict<'py>(py: Python<'py>, straight: &Mean, hook: &Mean) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item(
        "mean",
        PyArray1::from_slice(py, &[straight.mean, hook.mean]),
    )?;
    d.set_item("se", PyArray1::from_slice(py, &[straight.se, hook.se]))?;
    d.set_item("n", PyArray1::from_slice(py, &[straight.n, hook.n]))?;
    Ok(d)
}

/// The findings of a bowling study (its file's text): mean pins felled against the ball's
/// pin-line crossing, in bins of `bin_width` m (5 mm, thesis Fig. 7.10) across the window the
/// throws were aimed at — the CSV of `impulse bowling --from FILE --csv` — and the headline
/// figures its table prints. A dict of
/// - `lo`, `hi`: the bins' edges (m), shape (B,);
/// - `mean`: mean pins felled per bin, shape (B, 2), column 0 straight, column 1 hook (NaN
///   for a bin no throw of that kind crossed in); `se`: its standard error, shape (B, 2)
///   (NaN below two throws); `n`: the throws in each, shape (B, 2), int;
/// - `window`, `pocket` (+6 … +12 cm), `head_on` (|x| < 1.5 cm), `shoulders` (3 ≤ |x| <
///   9 cm): dicts of `mean`, `se`, `n`, each shape (2,), straight then hook;
/// - `throws` (outcomes in the file), `throws_per_kind`, `outside` (crossed outside the
///   window), `no_crossing`, `unsettled` (stopped at the settle time, counted as the pins
///   stood).
#[pyfunction]
#[pyo3(signature = (study, bin_width=BIN_WIDTH))]
fn bowling_summary<'py>(
    py: Python<'py>,
    study: &str,
    bin_width: f64,
) -> PyResult<Bound<'py, PyDict>> {
    if !(bin_width.is_finite() && bin_width > 0.0) {
        return Err(error(format!(
            "bin_width {bin_width}: must be a positive length (m)"
        )));
    }
    let file = read_study(study, 0).map_err(error)?;
    let window = file.settings.window();
    let (rows, sum) = py.detach(|| {
        (
            bowling::bins(&file.outcomes, window.0, window.1, bin_width),
            bowling::summarize(&file.outcomes, window),
        )
    });
    let column = |f: fn(&Mean) -> f64| -> Vec<[f64; 2]> {
        rows.iter().map(|r| [f(&r.straight), f(&r.hook)]).collect()
    };
    let d = PyDict::new(py);
    let edges = |f: fn(&bowling::BinRow) -> f64| rows.iter().map(f).collect::<Vec<f64>>();
    d.set_item("lo", PyArray1::from_vec(py, edges(|r| r.lo)))?;
    d.set_item("hi", PyArray1::from_vec(py, edges(|r| r.hi)))?;
    d.set_item(
        "mean",
        crate::rows_to_array(py, column(|m| m.mean).into_iter()),
    )?;
    d.set_item("se", crate::rows_to_array(py, column(|m| m.se).into_iter()))?;
    let counts: Vec<u64> = rows.iter().flat_map(|r| [r.straight.n, r.hook.n]).collect();
    let counts = Array2::from_shape_vec((rows.len(), 2), counts).expect("two counts per bin");
    d.set_item("n", counts.into_pyarray(py))?;
    d.set_item("window", band_dict(py, &sum.all.0, &sum.all.1)?)?;
    d.set_item(
        "pocket",
        band_dict(py, &sum.pocket_straight, &sum.pocket_hook)?,
    )?;
    d.set_item(
        "head_on",
        band_dict(py, &sum.head_on_straight, &sum.head_on_hook)?,
    )?;
    d.set_item(
        "shoulders",
        band_dict(py, &sum.shoulders_straight, &sum.shoulders_hook)?,
    )?;
    d.set_item("throws", file.outcomes.len())?;
    d.set_item("throws_per_kind", file.throws_per_kind)?;
    d.set_item("outside", sum.outside)?;
    d.set_item("no_crossing", sum.no_crossing)?;
    d.set_item("unsettled", sum.unsettled)?;
    Ok(d)
}

/// Adds this module's names to the extension module.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(run_bowling_shard, m)?)?;
    m.add_function(wrap_pyfunction!(bowling_throw_scene, m)?)?;
    m.add_function(wrap_pyfunction!(merge_bowling_studies, m)?)?;
    m.add_function(wrap_pyfunction!(bowling_summary, m)?)?;
    Ok(())
}
