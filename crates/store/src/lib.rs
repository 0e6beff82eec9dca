//! tactrace's files, one format a module, and the one configuration loader.
//!
//! - [`collection`]: a labelled collection of real frames (frames,
//!   detector, reference, target spec) and the one reader of its labels;
//! - [`dataset`]: `inputs.npy` / `targets.npy` / `meta.json` folders;
//!   [`image_frames`]: their optional `frames.npy` (the rows as images);
//!   [`dataset_join`]: several datasets as one training set, checked alike;
//! - [`model_dir`]: a trained model with the reference pins of its training
//!   data, loaded as one [`StoredModel`] so the pin-order check
//!   ([`pin_order`]) runs whenever a model meets data or a rig;
//!   [`image_model_dir`]: image model folders, and [`LoadedModel`], the
//!   one loader of either kind; both read and write the parts they share
//!   (network, training record, history, config) one way (`model_files`);
//! - [`training_record`]: which rows of which dataset a model was trained
//!   on (content hashes), so scores on training rows are told apart;
//! - [`frame_file`], [`shape_file`]: frames (PNG) and contours (CSV);
//! - [`sensor_file`]: calibrated sensor folders (`tactrace calibrate`);
//! - [`sight_file`]: sensor settings files (`tactrace sensor inspect`):
//!   how to read a TacTip's frames;
//! - [`config_file`]: defaults, then the file, unknown keys rejected
//!   ([`other_keys`]: also by a configuration made of flattened parts);
//! - [`fsutil`]: outputs that appear only when complete; [`lock`]: one
//!   writer per output;
//! - [`input_file`], [`npy_file`]: inputs read within bounds (regular files
//!   only, declared sizes checked against the file's); [`overlap`]: no
//!   output in or around an input;
//! - [`row_file`]: CSV files appended a whole row at a time; [`csv_text`]:
//!   whole CSV files through the csv crate.
//! - [`folder_kind`]: what a folder given in the wrong place is.
//!
//! Every error names the file at fault ([`StoreError`]).

pub mod collection;
pub mod config_file;
pub mod csv_text;
pub mod dataset;
pub mod dataset_join;
pub mod error;
pub mod folder_kind;
pub mod frame_file;
pub mod fsutil;
pub mod image_frames;
pub mod image_model_dir;
pub mod input_file;
pub mod lock;
pub mod model_dir;
mod model_files;
pub mod npy_file;
pub mod other_keys;
pub mod overlap;
pub mod pin_order;
pub mod row_file;
pub mod sensor_file;
pub mod shape_file;
pub mod sight_file;
pub mod tap_split;
mod toml_integers;
pub mod training_record;

pub use collection::{LabelledCollection, LabelledRow, TapFields, TargetSpec};
pub use config_file::{load_config, overlay, parse_toml, resolved_config_toml};
pub use csv_text::CsvText;
pub use dataset::{
    read_dataset, read_dataset_frames, write_dataset, write_dataset_with, DatasetMeta, TapData,
    TargetColumns, TrackTotals,
};
pub use dataset_join::{join_datasets, join_frames, DatasetMismatch};
pub use error::{read_err, write_err, Result, StoreError};
pub use fsutil::{
    check_output_dir, check_output_file, read_text, write_atomic, write_output_file, StagedDir,
};
pub use image_frames::{FramesInfo, ImageFrames};
pub use image_model_dir::{stage_image_model, LoadedModel, StoredImageModel};
pub use input_file::{open_regular, read_bounded};
pub use lock::OutputLock;
pub use model_dir::{stage_model, StoredModel};
pub use other_keys::NoOtherKeys;
pub use overlap::{check_output_apart, check_output_outside};
pub use pin_order::{pin_order_mismatch, PinOrderError};
pub use sensor_file::SensorFolder;
pub use shape_file::load_shape;
pub use sight_file::{SensorSummary, SightFile};
pub use training_record::{BaseFolds, DatasetId, HeldOut, TrainingRecord};
