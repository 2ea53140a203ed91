//! GPU timestamps around passes. One query pair per recorded span; resolved after the
//! frame's submission and read back as milliseconds.

use super::Gpu;
use crate::error::{Error, Result};

/// Collects (label, start, end) timestamp pairs for one frame.
pub struct GpuTimer {
    query_set: Option<wgpu::QuerySet>,
    resolve: Option<wgpu::Buffer>,
    readback: Option<wgpu::Buffer>,
    capacity: u32,
    labels: Vec<String>,
    period_ns: f64,
}

impl GpuTimer {
    /// `max_spans` bounds the spans per frame; without timestamp support every call is a no-op.
    pub fn new(gpu: &Gpu, max_spans: u32) -> GpuTimer {
        let capacity = max_spans * 2;
        let mut timer = GpuTimer {
            query_set: None,
            resolve: None,
            readback: None,
            capacity,
            labels: Vec::new(),
            period_ns: gpu.queue.get_timestamp_period() as f64,
        };
        if gpu.caps.timestamps {
            let bytes = capacity as u64 * 8;
            timer.query_set = Some(gpu.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("pass timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: capacity,
            }));
            timer.resolve = Some(gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamp resolve"),
                size: bytes,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }));
            timer.readback = Some(gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamp readback"),
                size: bytes,
                usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                mapped_at_creation: false,
            }));
        }
        timer
    }

    pub fn enabled(&self) -> bool {
        self.query_set.is_some()
    }

    /// Starts a new frame: forgets the previous frame's spans.
    pub fn reset(&mut self) {
        self.labels.clear();
    }

    /// Records the start of a span; returns its index for [`GpuTimer::end`].
    pub fn begin(&mut self, encoder: &mut wgpu::CommandEncoder, label: &str) -> Option<u32> {
        let qs = self.query_set.as_ref()?;
        let index = self.labels.len() as u32;
        if (index + 1) * 2 > self.capacity {
            log::warn!("timer full; span '{label}' is not timed");
            return None;
        }
        self.labels.push(label.to_string());
        encoder.write_timestamp(qs, index * 2);
        Some(index)
    }

    pub fn end(&mut self, encoder: &mut wgpu::CommandEncoder, span: Option<u32>) {
        if let (Some(qs), Some(index)) = (self.query_set.as_ref(), span) {
            encoder.write_timestamp(qs, index * 2 + 1);
        }
    }

    /// Copies this frame's queries into the readback buffer; call before `finish`.
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        if let (Some(qs), Some(resolve), Some(readback)) = (&self.query_set, &self.resolve, &self.readback) {
            let n = self.labels.len() as u32 * 2;
            if n == 0 {
                return;
            }
            encoder.resolve_query_set(qs, 0..n, resolve, 0);
            encoder.copy_buffer_to_buffer(resolve, 0, readback, 0, n as u64 * 8);
        }
    }

    /// Reads the spans of the submitted frame as (label, milliseconds). Waits for the GPU.
    pub fn read(&self, gpu: &Gpu) -> Result<Vec<(String, f64)>> {
        let Some(readback) = &self.readback else { return Ok(Vec::new()) };
        let n = self.labels.len() as u64 * 2;
        if n == 0 {
            return Ok(Vec::new());
        }
        let slice = readback.slice(..n * 8);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        gpu.wait_idle()?;
        rx.recv()
            .map_err(|_| Error::Gpu("timestamp callback never ran".into()))?
            .map_err(|e| Error::Gpu(format!("timestamp readback: {e}")))?;
        let ticks: Vec<u64> = {
            let data = slice.get_mapped_range().map_err(|e| Error::Gpu(format!("mapping a readback buffer: {e}")))?;
            data.chunks_exact(8).map(|c| u64::from_le_bytes(c.try_into().unwrap())).collect()
        };
        readback.unmap();
        Ok(self
            .labels
            .iter()
            .enumerate()
            .map(|(i, label)| {
                let ticks = ticks[2 * i + 1].saturating_sub(ticks[2 * i]);
                (label.clone(), ticks as f64 * self.period_ns * 1e-6)
            })
            .collect())
    }
}

/// One span's times over many frames.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SpanSummary {
    pub label: String,
    pub frames: usize,
    pub median_ms: f64,
    /// Interquartile range: the spread that one slow frame does not distort.
    pub p25_ms: f64,
    pub p75_ms: f64,
    pub min_ms: f64,
    pub max_ms: f64,
}

/// Median and spread of every span over frames, in the order spans first appear.
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
            let mut times: Vec<f64> =
                frames.iter().flat_map(|f| f.iter().filter(|(l, _)| l == label).map(|(_, ms)| *ms)).collect();
            times.sort_by(f64::total_cmp);
            SpanSummary {
                label: label.to_string(),
                frames: times.len(),
                median_ms: quantile(&times, 0.5),
                p25_ms: quantile(&times, 0.25),
                p75_ms: quantile(&times, 0.75),
                min_ms: times[0],
                max_ms: times[times.len() - 1],
            }
        })
        .collect()
}

/// Linear-interpolated quantile of sorted, non-empty values.
pub fn quantile(sorted: &[f64], q: f64) -> f64 {
    let pos = q.clamp(0.0, 1.0) * (sorted.len() - 1) as f64;
    let (i, frac) = (pos.floor() as usize, pos.fract());
    let next = sorted[(i + 1).min(sorted.len() - 1)];
    sorted[i] + (next - sorted[i]) * frac
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
        assert_eq!(quantile(&[1.0, 2.0], 0.5), 1.5);
    }
}
