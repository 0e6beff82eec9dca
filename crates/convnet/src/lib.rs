//! Images in, pose out: a convolutional dendritic network trained by
//! equilibrium propagation (`conv-dennn`), and its backprop twin
//! (`conv-mlp`: the same layers, initialisation and optimiser).
//!
//! Everything here is pure: no files, no printing. Models serialise to a
//! JSON string plus safetensors bytes; the caller writes them.
//! docs/learning.md ("Images in: the convolutional DenNN") gives the
//! equations and the choices.
mod activation;
mod adam;
mod augment;
mod config;
mod data;
mod dropout;
mod ep;
mod error;
mod fine_tune;
mod gemm;
mod hybrid;
mod im2col;
mod layout;
mod model;
pub mod model_file;
mod network;
mod params;
mod pass;
mod phases;
mod predict;
mod resample;
mod scaling;
mod serialise;
mod settle;
mod simd;
mod train;
mod turns;
mod workspace;

/// The building blocks of a layer as a matrix product, public for the
/// bench and for tests: im2col and its transpose, and the three products
/// (forward `W cols`, down `W^T e`, weights `e cols^T`), single-threaded,
/// and the steps around them: a layer's bias, potentials and rates in one
/// pass after its product ([`kernels::settle`]), col2im with the slope.
pub mod kernels {
    pub use crate::activation::{rates, times_slope};
    pub use crate::gemm::{add_product_nt, product, product_tn};
    pub use crate::im2col::{col2im, col2im_times_slope, im2col};
    pub use crate::settle::{settle, Errors, Settle};
}

pub use augment::PoseKeepingJitter;
pub use config::{
    Activation, ClampedPhase, ConvConfig, ConvSpec, EpSettings, FreePhase, InputCentring,
    InputKind, ModelKind, Nudging,
};
pub use data::{Frames, Targets};
pub use error::ConvError;
pub use layout::{LayerShape, Layout};
pub use model::ConvModel;
pub use network::{Equilibrium, Network, Rule};
pub use params::Parameters;
pub use predict::Predictor;
pub use resample::area_resample;
pub use scaling::{InputScaling, TargetScaling};
pub use serialise::CONV_FORMAT_VERSION;
pub use train::{EpochReport, TrainingHistory, Validation, DIVERGENCE_FACTOR};
pub use turns::{
    turn_angles, turn_frame, turn_vector, FrameTurns, TurnedColumns, TurnedVector, VectorColumns,
    MAX_TURN_ORDER,
};
