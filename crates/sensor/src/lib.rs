//! The TacTip optical tactile sensor, simulated and replayed.
//!
//! A hemispherical skin seen by an internal camera: the pin layout (a
//! hexagonal lattice, 127 pins by default, or concentric rings) and its
//! projection, a contact-mechanics model of the dome pressed onto
//! an extruded object (docs/sensor-model.md) or into any 3D object at any
//! tilt ([`TacTipModel::pins_3d`], docs/3d.md), fast anti-aliased rendering,
//! the [`TactileSensor`] trait with a simulated implementation
//! ([`SimTacTip`]), a replay implementation ([`ReplaySensor`]) and the
//! real-frame world's [`NearestFrameSensor`] (the saved real frame whose
//! labels, through a [`LabelConvention`], are nearest the tip's true pose).
//! Only the replay and nearest-frame sensors and [`read_frame`] touch files.

mod brush;
mod config;
mod contact;
mod contact3d;
mod correction;
mod edge_tap;
mod error;
mod fit;
mod fit_brush;
mod fit_convention;
mod fit_depth;
mod fit_joint;
mod fit_layout;
mod fit_rings;
mod label_convention;
mod layout;
mod model;
mod nearest;
mod nelder_mead;
mod render;
mod replay;
mod sensor;
mod sim;
mod slip;

pub use brush::{bristles, brush_slip, slide_path, REFERENCE_AREA_MM2};
pub use config::{
    Calibration, CameraConfig, Mechanics, Nuisance, PinLayout, SkinGeometry, SlipLaw, SlipSpread,
    TacTipConfig,
};
pub use contact::Shear;
pub use correction::FieldCorrection;
pub use edge_tap::EdgeTap;
pub use error::SensorError;
pub use fit::{field_misfit, fit_slip, FitSample, SlipFit, SlipParams};
pub use fit_brush::{fit_brush, BrushFit, BRUSH_PARAMS};
pub use fit_convention::{fit_convention, ConventionFit, ConventionScore, ConventionSearch};
pub use fit_depth::{fit_depth, DepthFit, DepthScore, DepthSearch};
pub use fit_joint::{fit_joint, JointFit, JOINT_PARAMS};
pub use fit_layout::{fit_layout, fit_layouts, KindFit, LayoutFit};
pub use label_convention::{wrap_deg, EdgeLabels, LabelConvention, ToolEdgePose};
pub use layout::{concentric_rings, hex_lattice, pin_count, skin_pins};
pub use model::TacTipModel;
pub use nearest::{edge_pose, Answer, FrameBank, LabelScales, LabelledFrame, NearestFrameSensor};
pub use nelder_mead::minimise;
pub use replay::{read_frame, read_image, ReplaySensor};
pub use sensor::{Frame, TactileSensor};
pub use sim::{PoseSource, SimTacTip};
pub use slip::{
    edge_bite, edge_slide, lag_profile, skin_lag, slip_field, slip_limit, ContactState,
    REFERENCE_LOAD_MM3,
};
