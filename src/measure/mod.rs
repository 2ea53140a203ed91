//! Measurement: the CPU reference tracer, image metrics, the bench and its budget fit,
//! the temporal and reprojection studies, stereo consistency, reports and plots. Builds
//! on `render` and `xr`, never on `app`.

pub mod analytic;
pub mod bench;
pub mod budget;
pub mod metrics;
pub mod plot;
pub mod reference;
pub mod reprojection;
pub mod stereo_consistency;
pub mod temporal;
