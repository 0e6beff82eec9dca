//! Measurement driver of issue 11's few-shot calibration, end to end with
//! the product's own datasets (`tactrace import` of the real frames,
//! `tactrace twin` of their labels; docs/calibration.md has the recipe).
//!
//! It joins real and twin taps by image name, assigns each frame to a part
//! of the project protocol by its number N in `frame_N_0.png` (score N%5=0,
//! select 1, fit 2-4), picks `--samples` calibration taps from the pool
//! parts with `select_taps`, fits the ridge correction, prints the field
//! misfit on the evaluation parts before and after, and writes the whole
//! twin, corrected, as a new dataset directory for `tactrace train`.
//!
//! ```text
//! cargo run --release -p tactrace-calib --example few_shot -- \
//!   --real /tmp/calib/real_all --real-csv $D/targets.csv \
//!   --twin /tmp/calib/twin --twin-csv $D/targets.csv \
//!   --pool fit --eval select --samples 100 --seed 1 --out /tmp/calib/cor100
//! ```
//! Options: `--pool`/`--eval` take part names joined by `+` (fit, select,
//! score), `--pool-where`/`--eval-where` an extra filter `theta<0`,
//! `theta>0`, `r<0` or `r>0`; `--samples all`; `--standardise`; `--rank K`;
//! `--add-real K|auto` (append the calibration real taps K times; `auto`:
//! `real_tap_repeats` of the first twin); `--noise-aug 1` (add a random
//! calibration residual to each twin tap); `--more-twins DIR,DIR` (twins of
//! the same labels with other render seeds, corrected and appended);
//! `--log10-penalty E` (a fixed penalty); `--force`. Without `--out` it
//! only measures.
use ndarray::Array2;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::time::Instant;
use tactrace_calib::{field_stats, select_taps, CorrectionParams, Fields, LinearCorrection};

type Res<T> = Result<T, Box<dyn std::error::Error>>;

/// One dataset aligned with the CSV it was made from: image name -> row.
struct Aligned {
    inputs: Array2<f32>,
    targets: Array2<f32>,
    rows: HashMap<String, usize>,
    dir: PathBuf,
}

/// Parsed command line.
struct Opts {
    args: HashMap<String, String>,
}

impl Opts {
    fn parse() -> Res<Self> {
        let mut args = HashMap::new();
        let mut it = std::env::args().skip(1).peekable();
        while let Some(key) = it.next() {
            let key = key
                .strip_prefix("--")
                .ok_or(format!("unexpected `{key}`"))?
                .to_string();
            let val = match it.peek() {
                Some(v) if !v.starts_with("--") => it.next().unwrap_or_default(),
                _ => "true".into(),
            };
            args.insert(key, val);
        }
        Ok(Opts { args })
    }
    fn get(&self, k: &str) -> Res<&str> {
        Ok(self.args.get(k).ok_or(format!("--{k} is required"))?)
    }
    fn or(&self, k: &str, d: &'static str) -> String {
        self.args.get(k).cloned().unwrap_or_else(|| d.into())
    }
}

fn main() -> Res<()> {
    let o = Opts::parse()?;
    let real = align(Path::new(o.get("real")?), Path::new(o.get("real-csv")?))?;
    let twin = align(Path::new(o.get("twin")?), Path::new(o.get("twin-csv")?))?;
    let names = joined_names(&real, &twin)?;
    let pool = part_rows(&names, &real, &o.or("pool", "fit"), &o.or("pool-where", ""))?;
    let eval = part_rows(
        &names,
        &real,
        &o.or("eval", "select"),
        &o.or("eval-where", ""),
    )?;
    if pool.iter().any(|n| eval.contains(n)) {
        return Err("pool and evaluation frames overlap".into());
    }
    let seed: u64 = o.or("seed", "1").parse()?;
    let labels: Vec<(f64, f64)> = pool.iter().map(|n| label(&real, n)).collect();
    let chosen: Vec<&String> = match o.or("samples", "all").as_str() {
        "all" => pool.iter().collect(),
        s => select_taps(&labels, s.parse()?, seed)?
            .into_iter()
            .map(|i| &pool[i])
            .collect(),
    };
    let t0 = Instant::now();
    let sim_c = fields(&twin, &chosen, "twin")?;
    let real_c = fields(&real, &chosen, "real")?;
    let fit = LinearCorrection::fit(&sim_c, &real_c, &params(&o)?)?;
    let fit_s = t0.elapsed().as_secs_f64();
    let eval: Vec<&String> = eval.iter().collect();
    let (sim_e, real_e) = (fields(&twin, &eval, "twin")?, fields(&real, &eval, "real")?);
    let before = field_stats(&sim_e, &real_e)?;
    let after = field_stats(&fit.correction.apply(&sim_e)?, &real_e)?;
    println!(
        "taps {} (pool {}) seed {seed} penalty {:.3e} loo {:.3} px, fit {fit_s:.3} s | eval {} taps: rms {:.3} -> {:.3} px, mean cos {:.4} -> {:.4}, median cos {:.4} -> {:.4}",
        chosen.len(), pool.len(), fit.penalty, fit.loo_rms, before.taps, before.rms_px, after.rms_px,
        before.mean_cosine, after.mean_cosine, before.median_cosine, after.median_cosine
    );
    if let Ok(n) = o.or("samples", "all").parse::<usize>() {
        time_calibrate(&twin, &real, &pool, &labels, n, seed)?;
    }
    if let Some(out) = o.args.get("out") {
        let resid = o
            .args
            .contains_key("noise-aug")
            .then(|| fit.correction.apply(&sim_c))
            .transpose()?;
        let resid = resid.map(|c| real_c.matrix() - c.matrix());
        let ex = extras(&o, &twin, &real, &chosen, resid, seed)?;
        write_corrected(&twin, &fit.correction, Path::new(out), &o, &ex)?;
        println!("wrote {out}");
    }
    Ok(())
}

/// The fit's settings from the options (default: the baseline ridge).
fn params(o: &Opts) -> Res<CorrectionParams> {
    let mut params = CorrectionParams {
        standardise: o.args.contains_key("standardise"),
        rank: o.args.get("rank").map(|r| r.parse()).transpose()?,
        ..Default::default()
    };
    if let Some(e) = o.args.get("log10-penalty") {
        (params.log10_min, params.log10_max, params.steps) = (e.parse()?, e.parse()?, 1);
    }
    Ok(params)
}

/// What the written training set holds besides the corrected twin.
fn extras<'a>(
    o: &Opts,
    twin: &Aligned,
    real: &'a Aligned,
    chosen: &[&'a String],
    resid: Option<nalgebra::DMatrix<f64>>,
    seed: u64,
) -> Res<Extras<'a>> {
    let copies = match o.args.get("add-real").map(String::as_str) {
        Some("auto") => tactrace_calib::real_tap_repeats(twin.inputs.nrows(), chosen.len()),
        Some(k) => k.parse()?,
        None => 0,
    };
    let mut twins = Vec::new();
    if let Some(list) = o.args.get("more-twins") {
        for dir in list.split(',') {
            twins.push(align(Path::new(dir), Path::new(o.get("twin-csv")?))?);
        }
    }
    Ok(Extras {
        twins,
        real: (
            real,
            (0..copies).flat_map(|_| chosen.iter().copied()).collect(),
        ),
        resid,
        seed,
    })
}

/// Read a dataset and align its rows with the CSV's image names. The
/// dataset does not carry image names; rows come in CSV order with rejected
/// frames left out, so each row is matched to the next CSV row whose
/// (r, theta) labels equal its targets exactly, and every row must match.
fn align(dir: &Path, csv_path: &Path) -> Res<Aligned> {
    let inputs: Array2<f32> = ndarray_npy::read_npy(dir.join("inputs.npy"))?;
    let targets: Array2<f32> = ndarray_npy::read_npy(dir.join("targets.npy"))?;
    let mut rdr = csv::Reader::from_path(csv_path)?;
    let h = rdr.headers()?.clone();
    let col = |n: &str| {
        h.iter()
            .position(|c| c == n)
            .ok_or(format!("no column {n}"))
    };
    let (ci, cr, ct) = (col("image_name")?, col("pose_2")?, col("pose_6")?);
    let mut rows = HashMap::new();
    let mut j = 0;
    for rec in rdr.records() {
        let rec = rec?;
        let (r, t): (f32, f32) = (rec[cr].trim().parse()?, rec[ct].trim().parse()?);
        if j < targets.nrows() && targets[[j, 0]] == r && targets[[j, 1]] == t {
            rows.insert(rec[ci].to_string(), j);
            j += 1;
        }
    }
    if j != targets.nrows() {
        return Err(format!(
            "{}: only {j} of {} rows match {}",
            dir.display(),
            targets.nrows(),
            csv_path.display()
        )
        .into());
    }
    eprintln!(
        "{}: {} rows aligned with {} by label order",
        dir.display(),
        j,
        csv_path.display()
    );
    Ok(Aligned {
        inputs,
        targets,
        rows,
        dir: dir.into(),
    })
}

/// Image names present in both, sorted by frame number.
fn joined_names(real: &Aligned, twin: &Aligned) -> Res<Vec<String>> {
    let mut names: Vec<String> = real
        .rows
        .keys()
        .filter(|n| twin.rows.contains_key(*n))
        .cloned()
        .collect();
    names.sort_by_key(|n| frame_number(n).unwrap_or(usize::MAX));
    for n in &names {
        let (a, b) = (label(real, n), label(twin, n));
        if a != b {
            return Err(format!("{n}: real labels {a:?} vs twin {b:?}").into());
        }
    }
    eprintln!(
        "joined {} taps by image name (real {}, twin {})",
        names.len(),
        real.rows.len(),
        twin.rows.len()
    );
    Ok(names)
}

/// N of `frame_N_0.png`.
fn frame_number(name: &str) -> Option<usize> {
    name.strip_prefix("frame_")?.split('_').next()?.parse().ok()
}

/// The names in the `+`-joined parts that pass `filter`.
fn part_rows(names: &[String], real: &Aligned, parts: &str, filter: &str) -> Res<Vec<String>> {
    let mut mods = Vec::new();
    for p in parts.split('+') {
        mods.extend(match p {
            "score" => vec![0],
            "select" => vec![1],
            "fit" => vec![2, 3, 4],
            _ => return Err(format!("unknown part `{p}` (score, select, fit)").into()),
        });
    }
    let keep = |n: &String| -> bool {
        let (r, t) = label(real, n);
        match filter {
            "" => true,
            "theta<0" => t < 0.0,
            "theta>0" => t > 0.0,
            "r<0" => r < 0.0,
            "r>0" => r > 0.0,
            _ => false,
        }
    };
    if !["", "theta<0", "theta>0", "r<0", "r>0"].contains(&filter) {
        return Err(format!("unknown filter `{filter}`").into());
    }
    Ok(names
        .iter()
        .filter(|n| frame_number(n).is_some_and(|k| mods.contains(&(k % 5))) && keep(n))
        .cloned()
        .collect())
}

fn label(d: &Aligned, name: &str) -> (f64, f64) {
    let j = d.rows[name];
    (d.targets[[j, 0]] as f64, d.targets[[j, 1]] as f64)
}

/// The fields of `names`, in that order.
fn fields(d: &Aligned, names: &[&String], what: &str) -> Res<Fields> {
    let mut flat = Vec::with_capacity(names.len() * d.inputs.ncols());
    for n in names {
        flat.extend(d.inputs.row(d.rows[n.as_str()]).iter().copied());
    }
    Ok(Fields::from_flat(&flat, d.inputs.ncols(), what)?)
}

/// What the written training set holds besides the corrected twin.
struct Extras<'a> {
    /// Further twins of the same labels (other render seeds), also corrected.
    twins: Vec<Aligned>,
    /// Real taps appended as they are (`--add-real`: the calibration taps K times).
    real: (&'a Aligned, Vec<&'a String>),
    /// Calibration residuals, one added at random to each twin tap (`--noise-aug`).
    resid: Option<nalgebra::DMatrix<f64>>,
    seed: u64,
}

/// Every twin tap corrected, then the extras, with the twin's meta (marked).
fn write_corrected(
    twin: &Aligned,
    corr: &LinearCorrection,
    out: &Path,
    o: &Opts,
    ex: &Extras,
) -> Res<()> {
    if out.exists() && out.read_dir()?.next().is_some() && !o.args.contains_key("force") {
        return Err(format!(
            "{} exists and is not empty (--force replaces it)",
            out.display()
        )
        .into());
    }
    std::fs::create_dir_all(out)?;
    let (mut inputs, mut targets) = (Vec::new(), Vec::new());
    for t in std::iter::once(twin).chain(&ex.twins) {
        let all = Fields::from_flat(
            t.inputs.as_slice().ok_or("inputs not contiguous")?,
            t.inputs.ncols(),
            "twin",
        )?;
        let mut fixed = corr.apply(&all)?.to_flat();
        if let Some(e) = &ex.resid {
            add_residuals(&mut fixed, all.dim(), e, ex.seed);
        }
        inputs.extend(fixed);
        targets.extend(t.targets.iter().copied());
    }
    let (real, names) = (ex.real.0, &ex.real.1);
    let refs: Vec<&String> = names.to_vec();
    inputs.extend(fields(real, &refs, "real")?.to_flat());
    for n in names {
        targets.extend(real.targets.row(real.rows[n.as_str()]).iter());
    }
    let rows = targets.len() / 2;
    let arr = Array2::from_shape_vec((rows, twin.inputs.ncols()), inputs)?;
    ndarray_npy::write_npy(out.join("inputs.npy"), &arr)?;
    ndarray_npy::write_npy(
        out.join("targets.npy"),
        &Array2::from_shape_vec((rows, 2), targets)?,
    )?;
    let mut meta: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(twin.dir.join("meta.json"))?)?;
    meta["samples"] = rows.into();
    meta["source"] = "simulated twin, linear correction (tactrace-calib few_shot)".into();
    let args: serde_json::Map<String, serde_json::Value> = o
        .args
        .iter()
        .map(|(k, v)| (k.clone(), v.clone().into()))
        .collect();
    meta["settings"]["calibration"] = serde_json::Value::Object(args);
    std::fs::write(out.join("meta.json"), serde_json::to_string_pretty(&meta)?)?;
    Ok(())
}

/// Add to each field (rows of `d` values) one residual row of `e` drawn at random.
fn add_residuals(flat: &mut [f32], d: usize, e: &nalgebra::DMatrix<f64>, seed: u64) {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    for row in flat.chunks_mut(d) {
        let j = rng.random_range(0..e.nrows());
        for (k, v) in row.iter_mut().enumerate() {
            *v += e[(j, k)] as f32;
        }
    }
}

/// Time the library's whole `calibrate` on the pool (select, span check,
/// fit, score on the pool's other taps), as `tactrace calibrate` will run it.
fn time_calibrate(
    twin: &Aligned,
    real: &Aligned,
    pool: &[String],
    labels: &[(f64, f64)],
    n: usize,
    seed: u64,
) -> Res<()> {
    let names: Vec<&String> = pool.iter().collect();
    let (sim, re) = (fields(twin, &names, "twin")?, fields(real, &names, "real")?);
    let plan = tactrace_calib::CalibrationPlan {
        samples: Some(n),
        seed,
        ..Default::default()
    };
    let t0 = Instant::now();
    let cal = tactrace_calib::calibrate(&sim, &re, labels, &plan)?;
    let (b, a) = (cal.record.held_out_before, cal.record.held_out_after);
    println!(
        "calibrate(): {n} of {} taps in {:.3} s; the pool's other taps: rms {:.3} -> {:.3} px",
        pool.len(),
        t0.elapsed().as_secs_f64(),
        b.map_or(f64::NAN, |s| s.rms_px),
        a.map_or(f64::NAN, |s| s.rms_px)
    );
    Ok(())
}
