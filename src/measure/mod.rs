//! Measurement: the CPU reference tracer, image metrics, the bench and its budget fit,
//! the temporal and reprojection studies, stereo consistency, the GPU table, reports and
//! plots. Builds on `render` and `xr`, never on `app`.

// Closed-form and quadrature expectations the tests compare the GPU against: a test
// oracle, built for the crate's own tests and with the `testing` feature (which the
// integration tests turn on through the dev-dependency on vrao itself).
#[cfg(any(test, feature = "testing"))]
pub mod analytic;
pub mod bench;
pub mod budget;
pub mod metrics;
pub mod peer;
pub mod plot;
pub mod reference;
pub mod reprojection;
pub mod side_by_side;
pub mod stereo_consistency;
pub mod table;
pub mod temporal;

use crate::error::{Error, Result};

/// The most warm-up frames a measurement takes (`--warmup` of bench and budget): a few
/// suffice for pipeline compilation and first-touch allocation.
pub const WARMUP_MAX: u32 = 1000;
/// The most measured frames per case (`--frames` of bench and budget).
pub const MEASURED_FRAMES_MAX: u32 = 100_000;

/// Refuses warm-up and measured frame counts out of 0..=[`WARMUP_MAX`] and
/// 1..=[`MEASURED_FRAMES_MAX`] (no measurement without a measured frame, none that runs
/// for days).
pub fn check_frames(warmup: u32, frames: u32) -> Result<()> {
    if warmup > WARMUP_MAX {
        return Err(Error::input(format!("warm-up of {warmup} frames is not within 0..={WARMUP_MAX}")));
    }
    if !(1..=MEASURED_FRAMES_MAX).contains(&frames) {
        return Err(Error::input(format!("{frames} measured frames is not within 1..={MEASURED_FRAMES_MAX}")));
    }
    Ok(())
}

/// The first value a sweep's list names twice (its rows would be measured twice), if any.
pub fn named_twice<T: PartialEq>(list: &[T]) -> Option<&T> {
    list.iter().enumerate().find(|(i, v)| list[..*i].contains(v)).map(|(_, v)| v)
}

#[cfg(test)]
mod tests {
    #[test]
    fn frame_counts_are_bounded_both_ways() {
        assert!(super::check_frames(0, 1).is_ok());
        assert!(super::check_frames(super::WARMUP_MAX, super::MEASURED_FRAMES_MAX).is_ok());
        let e = super::check_frames(u32::MAX, 1).unwrap_err().to_string();
        assert!(e.contains("4294967295") && e.contains("0..=1000"), "{e}");
        assert!(super::check_frames(3, 0).is_err());
    }
}
