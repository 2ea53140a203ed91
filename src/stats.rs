//! The one definition of a quantile (and so of a median and a percentile) that every
//! report of vrao uses: per-pass GPU times, the run summary, the headsets' latency.
//!
//! The q-quantile of n sorted values x₀ ≤ … ≤ xₙ₋₁ interpolates linearly between the
//! closest ranks (Hyndman & Fan's type 7, the default of R and NumPy): with
//! h = q·(n − 1), it is x⌊h⌋ + (h − ⌊h⌋)·(x⌊h⌋₊₁ − x⌊h⌋). The median of an even count is
//! the mean of the middle two; q = 0 and q = 1 are the minimum and maximum. Nearest rank
//! would jump between samples as q moves, which makes a p95 of few frames jumpy.

/// Values sorted once, for several quantiles of them. NaN sorts after every number
/// (`f64::total_cmp`), so it shows up in the top quantiles instead of vanishing.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Sorted(Vec<f64>);

impl Sorted {
    /// The values, sorted.
    pub fn new(values: impl IntoIterator<Item = f64>) -> Sorted {
        let mut values: Vec<f64> = values.into_iter().collect();
        values.sort_by(f64::total_cmp);
        Sorted(values)
    }

    /// The q-quantile (q clamped to 0..=1) by the module's definition; `None` when there
    /// are no values.
    pub fn quantile(&self, q: f64) -> Option<f64> {
        let sorted = &self.0;
        let last = sorted.len().checked_sub(1)?;
        let h = q.clamp(0.0, 1.0) * last as f64;
        let (i, frac) = (h.floor() as usize, h.fract());
        let next = sorted[(i + 1).min(last)];
        // frac == 0 returns the sample itself (no 0 × ∞ at an infinite neighbour).
        Some(if frac == 0.0 { sorted[i] } else { sorted[i] + (next - sorted[i]) * frac })
    }

    /// The median (the 0.5-quantile).
    pub fn median(&self) -> Option<f64> {
        self.quantile(0.5)
    }

    /// The smallest value.
    pub fn min(&self) -> Option<f64> {
        self.0.first().copied()
    }

    /// The largest value.
    pub fn max(&self) -> Option<f64> {
        self.0.last().copied()
    }

    /// How many values there are.
    pub fn len(&self) -> usize {
        self.0.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }
}

/// The q-quantile of `values` in any order ([`Sorted::quantile`]); `None` when empty.
pub fn quantile(values: &[f64], q: f64) -> Option<f64> {
    Sorted::new(values.iter().copied()).quantile(q)
}

/// The median of `values` in any order; `None` when empty.
pub fn median(values: &[f64]) -> Option<f64> {
    quantile(values, 0.5)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantiles_interpolate_between_closest_ranks() {
        // 1..=5 in any order: h = q·4, so the 0.95-quantile is 4 + 0.8·(5 − 4) = 4.8
        // (nearest rank would say 5), the quartiles are 2 and 4.
        let s = Sorted::new([3.0, 1.0, 5.0, 2.0, 4.0]);
        assert_eq!(s.median(), Some(3.0));
        assert_eq!(s.quantile(0.25), Some(2.0));
        assert_eq!(s.quantile(0.75), Some(4.0));
        assert!((s.quantile(0.95).unwrap() - 4.8).abs() < 1e-12);
        assert_eq!((s.quantile(0.0), s.quantile(1.0)), (Some(1.0), Some(5.0)));
        assert_eq!((s.min(), s.max(), s.len()), (Some(1.0), Some(5.0), 5));
        // Out-of-range q clamps to the extremes.
        assert_eq!((s.quantile(-1.0), s.quantile(2.0)), (Some(1.0), Some(5.0)));
    }

    #[test]
    fn an_even_count_has_the_mean_of_the_middle_two_as_median() {
        assert_eq!(median(&[10.0, 0.0, 4.0, 2.0]), Some(3.0));
        assert_eq!(median(&[1.0, 2.0]), Some(1.5));
        // 0.1-quantile of 0, 10, 20, 30, 40 (h = 0.4): 4.
        assert!((quantile(&[40.0, 30.0, 20.0, 10.0, 0.0], 0.1).unwrap() - 4.0).abs() < 1e-12);
    }

    #[test]
    fn one_value_is_every_quantile_and_none_has_none() {
        assert_eq!(quantile(&[7.0], 0.95), Some(7.0));
        assert_eq!(median(&[]), None);
        assert!(Sorted::new([]).is_empty());
        assert_eq!(Sorted::new([]).quantile(0.5), None);
    }

    #[test]
    fn infinities_at_exact_ranks_do_not_spoil_the_rest() {
        let s = Sorted::new([1.0, 2.0, f64::INFINITY]);
        assert_eq!(s.median(), Some(2.0));
        assert_eq!(s.max(), Some(f64::INFINITY));
    }
}
