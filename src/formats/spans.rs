//! Median and spread of GPU and CPU spans over many frames, for reports.

use crate::stats::Sorted;

/// One span's times over many frames.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SpanSummary {
    /// The span's label (a pass name, or a per-eye span such as `ssao/left`).
    pub label: String,
    /// Frames the span was seen in.
    pub frames: usize,
    /// Median GPU ms.
    pub median_ms: f64,
    /// Interquartile range: the spread that one slow frame does not distort.
    pub p25_ms: f64,
    /// 75th percentile GPU ms (with `p25_ms`, the interquartile range).
    pub p75_ms: f64,
    /// Fastest frame's GPU ms.
    pub min_ms: f64,
    /// Slowest frame's GPU ms.
    pub max_ms: f64,
}

/// Median and spread of every span over frames, in the order spans first appear
/// (quantiles as [`crate::stats`] defines them).
pub fn summarize(frames: &[Vec<(String, f64)>]) -> Vec<SpanSummary> {
    let mut labels: Vec<&str> = Vec::new();
    for frame in frames {
        for (label, _) in frame {
            if !labels.contains(&label.as_str()) {
                labels.push(label);
            }
        }
    }
    labels
        .into_iter()
        .map(|label| {
            let times =
                Sorted::new(frames.iter().flat_map(|f| f.iter().filter(|(l, _)| l == label).map(|(_, ms)| *ms)));
            // Every label was seen in some frame, so it has at least one time.
            let at = |q: f64| times.quantile(q).expect("a label comes from a frame");
            SpanSummary {
                label: label.to_string(),
                frames: times.len(),
                median_ms: at(0.5),
                p25_ms: at(0.25),
                p75_ms: at(0.75),
                min_ms: at(0.0),
                max_ms: at(1.0),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_and_quartiles_of_spans() {
        let frames: Vec<Vec<(String, f64)>> = [1.0, 5.0, 2.0, 4.0, 3.0]
            .iter()
            .map(|&ms| vec![("a".to_string(), ms), ("b".to_string(), 10.0 * ms)])
            .collect();
        let s = summarize(&frames);
        assert_eq!(s.len(), 2);
        assert_eq!((s[0].median_ms, s[0].p25_ms, s[0].p75_ms, s[0].min_ms, s[0].max_ms), (3.0, 2.0, 4.0, 1.0, 5.0));
        assert_eq!(s[1].median_ms, 30.0);
    }
}

/// The right eye's computed tiles against all its tiles in one pass (the left eye
/// computes every one of its own), as `vrao budget`'s and `vrao run`'s reports give them.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize, PartialEq)]
pub struct RightEyeTilesReport {
    /// The pass.
    pub pass: String,
    /// Tiles (workgroups of 64 items) the right eye computed in the last stereo frame.
    pub computed: u32,
    /// The items it computed (pixels; quads of 2×2 for the upsampling); it copied the rest.
    pub items: u32,
    /// Tiles of the right eye's occlusion image.
    pub total: u32,
    /// `computed / total`: the right eye's share of the left eye's work, in tiles.
    pub share: f64,
}

impl From<&vrao_ao::RightEyeTiles> for RightEyeTilesReport {
    fn from(t: &vrao_ao::RightEyeTiles) -> RightEyeTilesReport {
        RightEyeTilesReport {
            pass: t.pass.to_string(),
            computed: t.computed,
            items: t.items,
            total: t.total,
            share: t.share(),
        }
    }
}
