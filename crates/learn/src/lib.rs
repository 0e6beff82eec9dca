//! The brain of tactrace (report ch. 3 and 4.2-4.3): standardisation and PCA
//! of pin displacements, dendritic neural networks trained by equilibrium
//! propagation, a backprop twin for comparison, and pose models that map one
//! displacement vector to N named targets in mm or degrees (circular angles
//! learnt as sine and cosine), the edge pose `[r mm, theta deg]` among them.
//!
//! Image models (one grey frame in: `conv-dennn`, `conv-mlp`) wrap the
//! convolutional networks of `tactrace_convnet` over the same targets
//! ([`ImageModel`]).
//!
//! Everything here is pure: no files, no printing. Models serialise to a JSON
//! string plus safetensors bytes; the lab crate writes them.
mod band_weight;
mod closed_form;
mod config;
mod continued;
mod cost;
mod dataset;
mod deep_clamp;
mod dennn;
mod ep;
mod error;
mod fit_members;
mod image_base;
mod image_model;
mod joined;
mod kernels;
mod member;
mod mlp;
mod net;
mod pca;
mod peak;
mod pin_features;
mod pose_model;
mod predict;
mod reflections;
mod rotations;
mod search;
mod serialise;
mod setting_difference;
mod standardise;
mod target_score;
mod targets;
mod trainer;
mod turned_views;

pub use band_weight::{BandWeight, MAX_BAND_WEIGHT};
pub use config::{
    ModelConfig, ModelKind, NetConfig, Preset, TargetScaling, MAX_ENSEMBLE, MAX_SEED,
};
pub use continued::check_continuable;
pub use cost::{Cost, CostKind, NetCost};
pub use dataset::{mean_absolute_error, Dataset};
pub use dennn::{ClampedPhase, DenNN, EpConfig, FreePhase, LrScaling, SampleStats};
pub use error::LearnError;
pub use image_base::BaseFit;
pub use image_model::{is_image_model_json, ImageModel, IMAGE_FORMAT, IMAGE_FORMAT_VERSION};
pub use mlp::Mlp;
pub use net::Layers;
pub use pca::{Components, PcScaling, Pca};
pub use peak::{measure_fma_peak, FmaPeak};
pub use pin_features::{FeatureMap, PinFeatures, NEIGHBOURS};
pub use pose_model::{EpochReport, NetEpoch, PoseModel, TrainingHistory};
pub use reflections::{mirror_pins, mirrored_copies, mirrored_inputs, Reflections};
pub use rotations::{turned_copies, Rotations, MATCH_TOLERANCE, MAX_ORDER};
pub use search::{hyperparameter_search, SearchSpace, Trial, MAX_GRID_POINTS};
pub use serialise::FORMAT_VERSION;
pub use setting_difference::{first_difference, first_setting_difference, SettingDifference};
pub use standardise::Standardiser;
pub use target_score::{target_spread, TargetScale};
pub use targets::{
    check_targets, decode, edge_roles, edge_targets, encode_into, encoded_columns, names_the_edge,
    target_mae, wrap_deg, ModelTarget, Role, Unit,
};
