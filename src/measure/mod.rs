//! Measurement: the CPU reference tracer, image metrics, the bench and its budget fit,
//! the temporal and reprojection studies, stereo consistency, reports and plots. Builds
//! on `render` and `xr`, never on `app`.

// Closed-form and quadrature expectations the tests compare the GPU against: a test
// oracle, built for the crate's own tests and with the `testing` feature (which the
// integration tests turn on through the dev-dependency on vrao itself).
#[cfg(any(test, feature = "testing"))]
pub mod analytic;
pub mod bench;
pub mod budget;
pub mod metrics;
pub mod plot;
pub mod reference;
pub mod reprojection;
pub mod stereo_consistency;
pub mod temporal;
