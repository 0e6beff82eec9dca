//! The file kinds the CLI reads, each with its seed and the commands that
//! read it. In arguments `{base}` is the seed folder and `{case}` the
//! folder of one mutated input.
use super::mutate::Format;

/// One kind of input file.
pub struct Kind {
    pub name: &'static str,
    /// The seed file, relative to `{base}`.
    pub seed: &'static str,
    /// Where the mutant goes, relative to `{case}`.
    pub target: &'static str,
    pub format: Format,
    /// A seed folder copied to `{case}` first (files only), for inputs that
    /// are one file of a folder (dataset, model, frames).
    pub copy_dir: Option<(&'static str, &'static str)>,
    /// Commands reading the mutant; one is picked per input, in turn.
    pub commands: &'static [&'static [&'static str]],
}

const PINS: &[&str] = &["sensor", "pins", "{case}/in.png", "--preset", "sim"];
const PREDICT_IMAGE: &[&str] = &[
    "predict",
    "--model",
    "{base}/m",
    "--image",
    "{case}/in.png",
    "--reference",
    "{base}/ref.png",
];
const PREDICT_REF: &[&str] = &[
    "predict",
    "--model",
    "{base}/m",
    "--image",
    "{base}/tap.png",
    "--reference",
    "{case}/in.png",
];
const IMPORT_FRAMES: &[&str] = &[
    "import",
    "--frames",
    "{case}/frames",
    "--targets",
    "{base}/bristol/targets.csv",
    "--reference",
    "{case}/frames/init_0.png",
    "--out",
    "{case}/out",
];
const IMPORT_TARGETS: &[&str] = &[
    "import",
    "--frames",
    "{base}/bristol/frames",
    "--targets",
    "{case}/targets.csv",
    "--reference",
    "{base}/bristol/frames/init_0.png",
    "--out",
    "{case}/out",
];
const TWIN_TARGETS: &[&str] = &[
    "twin",
    "--targets",
    "{case}/targets.csv",
    "--reference",
    "{base}/bristol/frames/init_0.png",
    "--out",
    "{case}/out",
];
const RENDER_SHAPE: &[&str] = &[
    "sensor",
    "render",
    "--shape",
    "{case}/in.csv",
    "--out",
    "{case}/o.png",
];
const FOLLOW_SHAPE: &[&str] = &[
    "follow",
    "--model",
    "{base}/m",
    "--shape",
    "{case}/in.csv",
    "--steps",
    "3",
    "--out",
    "{case}/run",
];
const COLLECT_SHAPE: &[&str] = &[
    "collect",
    "--shape",
    "{case}/in.csv",
    "--samples",
    "3",
    "--out",
    "{case}/ds",
];
const PINS_PARAMS: &[&str] = &[
    "sensor",
    "pins",
    "{base}/tap.png",
    "--params",
    "{case}/in.toml",
];
const PREDICT_PARAMS: &[&str] = &[
    "predict",
    "--model",
    "{base}/m",
    "--image",
    "{base}/tap.png",
    "--reference",
    "{base}/ref.png",
    "--params",
    "{case}/in.toml",
];
const COLLECT_RIG: &[&str] = &[
    "collect",
    "--config",
    "{case}/in.toml",
    "--samples",
    "3",
    "--out",
    "{case}/ds",
];
const RENDER_RIG: &[&str] = &[
    "sensor",
    "render",
    "--config",
    "{case}/in.toml",
    "--r",
    "1",
    "--out",
    "{case}/o.png",
];
const FOLLOW_CONFIG: &[&str] = &[
    "follow",
    "--model",
    "{base}/m",
    "--shape",
    "disk",
    "--steps",
    "3",
    "--config",
    "{case}/in.toml",
    "--out",
    "{case}/run",
];
const TRAIN_CONFIG: &[&str] = &[
    "train",
    "--train",
    "{base}/ds",
    "--epochs",
    "1",
    "--config",
    "{case}/in.toml",
    "--out",
    "{case}/m",
];
const TRAIN_SEARCH: &[&str] = &[
    "train",
    "--model",
    "disdennn",
    "--train",
    "{base}/ds",
    "--epochs",
    "1",
    "--search",
    "--search-space",
    "{case}/in.toml",
    "--out",
    "{case}/m",
];
const VALIDATE_DATA: &[&str] = &[
    "validate",
    "--model",
    "{base}/m",
    "--data",
    "{case}/ds",
    "--json",
];
const PREDICT_DATA: &[&str] = &["predict", "--model", "{base}/m", "--data", "{case}/ds"];
const TRAIN_DATA: &[&str] = &[
    "train",
    "--train",
    "{case}/ds",
    "--epochs",
    "1",
    "--out",
    "{case}/m",
];
const TRAIN_VAL: &[&str] = &[
    "train",
    "--model",
    "mlp",
    "--train",
    "{base}/ds",
    "--val",
    "{case}/ds",
    "--epochs",
    "1",
    "--out",
    "{case}/m",
];
const VALIDATE_MODEL: &[&str] = &["validate", "--model", "{case}/m", "--data", "{base}/ds"];
const PREDICT_MODEL: &[&str] = &[
    "predict",
    "--model",
    "{case}/m",
    "--image",
    "{base}/tap.png",
    "--reference",
    "{base}/ref.png",
];
const FOLLOW_MODEL: &[&str] = &[
    "follow",
    "--model",
    "{case}/m",
    "--shape",
    "disk",
    "--steps",
    "3",
    "--out",
    "{case}/run",
];
const BENCH_MODEL: &[&str] = &["bench", "--taps", "2", "--model", "{case}/m"];

const DATA: &[&[&str]] = &[VALIDATE_DATA, PREDICT_DATA, TRAIN_DATA, TRAIN_VAL];
const MODEL: &[&[&str]] = &[VALIDATE_MODEL, PREDICT_MODEL, FOLLOW_MODEL, BENCH_MODEL];

/// A kind whose mutant is one file of a copied folder.
const fn in_dir(
    name: &'static str,
    seed: &'static str,
    target: &'static str,
    format: Format,
    dir: (&'static str, &'static str),
    commands: &'static [&'static [&'static str]],
) -> Kind {
    Kind {
        name,
        seed,
        target,
        format,
        copy_dir: Some(dir),
        commands,
    }
}

/// A kind whose mutant is a lone file.
const fn alone(
    name: &'static str,
    seed: &'static str,
    target: &'static str,
    format: Format,
    commands: &'static [&'static [&'static str]],
) -> Kind {
    Kind {
        name,
        seed,
        target,
        format,
        copy_dir: None,
        commands,
    }
}

/// Every kind, in the order inputs are dealt out.
pub const KINDS: &[Kind] = &[
    alone(
        "frame",
        "tap.png",
        "in.png",
        Format::Png,
        &[PINS, PREDICT_IMAGE],
    ),
    alone(
        "reference-frame",
        "ref.png",
        "in.png",
        Format::Png,
        &[PREDICT_REF],
    ),
    in_dir(
        "bristol-frame",
        "bristol/frames/frame_1_0.png",
        "frames/frame_1_0.png",
        Format::Png,
        ("bristol/frames", "frames"),
        &[IMPORT_FRAMES],
    ),
    in_dir(
        "bristol-reference",
        "bristol/frames/init_0.png",
        "frames/init_0.png",
        Format::Png,
        ("bristol/frames", "frames"),
        &[IMPORT_FRAMES],
    ),
    alone(
        "contour-csv",
        "contour.csv",
        "in.csv",
        Format::Csv,
        &[RENDER_SHAPE, FOLLOW_SHAPE, COLLECT_SHAPE],
    ),
    alone(
        "targets-csv",
        "bristol/targets.csv",
        "targets.csv",
        Format::Csv,
        &[IMPORT_TARGETS, TWIN_TARGETS],
    ),
    alone(
        "blob-toml",
        "blob.toml",
        "in.toml",
        Format::Toml,
        &[PINS_PARAMS, PREDICT_PARAMS],
    ),
    alone(
        "rig-toml",
        "rig.toml",
        "in.toml",
        Format::Toml,
        &[COLLECT_RIG, RENDER_RIG],
    ),
    alone(
        "follow-toml",
        "follow.toml",
        "in.toml",
        Format::Toml,
        &[FOLLOW_CONFIG],
    ),
    alone(
        "train-toml",
        "train.toml",
        "in.toml",
        Format::Toml,
        &[TRAIN_CONFIG],
    ),
    alone(
        "search-toml",
        "search.toml",
        "in.toml",
        Format::Toml,
        &[TRAIN_SEARCH],
    ),
    in_dir(
        "inputs-npy",
        "ds/inputs.npy",
        "ds/inputs.npy",
        Format::Array,
        ("ds", "ds"),
        DATA,
    ),
    in_dir(
        "targets-npy",
        "ds/targets.npy",
        "ds/targets.npy",
        Format::Array,
        ("ds", "ds"),
        DATA,
    ),
    in_dir(
        "meta-json",
        "ds/meta.json",
        "ds/meta.json",
        Format::Json,
        ("ds", "ds"),
        DATA,
    ),
    in_dir(
        "model-json",
        "m/model.json",
        "m/model.json",
        Format::Json,
        ("m", "m"),
        MODEL,
    ),
    in_dir(
        "model-safetensors",
        "m/weights.safetensors",
        "m/weights.safetensors",
        Format::Array,
        ("m", "m"),
        MODEL,
    ),
    in_dir(
        "model-pins-json",
        "m/pins.json",
        "m/pins.json",
        Format::Json,
        ("m", "m"),
        MODEL,
    ),
];
