//! Accessors decoded by hand: every byte range checked against its buffer view and
//! buffer before it is read (the crate's readers assume valid ranges).

use super::{Loader, MAX_ACCESSOR_COUNT};
use crate::error::Result;
use ::gltf::accessor::{DataType, Dimensions};

impl Loader<'_> {
    /// The bytes an accessor reads, checked against its view and buffer: (bytes from the
    /// accessor's first element, stride, element size). `None` for an accessor without a
    /// buffer view (all zeros, per the spec).
    pub(super) fn accessor_bytes(
        &self,
        accessor: &::gltf::Accessor,
        what: &str,
    ) -> Result<Option<(&[u8], usize, usize)>> {
        let index = accessor.index();
        if accessor.sparse().is_some() {
            return Err(self.error(format!("{what}: accessor {index} is sparse, which vrao does not read")));
        }
        let count = accessor.count();
        if count > MAX_ACCESSOR_COUNT {
            return Err(self.error(format!(
                "{what}: accessor {index} declares {count} elements (vrao's limit: {MAX_ACCESSOR_COUNT})"
            )));
        }
        let element = accessor.dimensions().multiplicity() * accessor.data_type().size();
        let Some(view) = accessor.view() else { return Ok(None) };
        let buffer = &self.buffers[view.buffer().index()];
        let view_end =
            view.offset().checked_add(view.length()).filter(|&end| end <= buffer.len()).ok_or_else(|| {
                self.error(format!(
                    "buffer view {} (bytes {}..+{}) runs past the end of buffer {} ({} bytes)",
                    view.index(),
                    view.offset(),
                    view.length(),
                    view.buffer().index(),
                    buffer.len()
                ))
            })?;
        let stride = view.stride().unwrap_or(element);
        if stride < element {
            return Err(
                self.error(format!("{what}: accessor {index} stride {stride} is less than its element size {element}"))
            );
        }
        let needed = match count {
            0 => Some(accessor.offset()),
            n => (n - 1).checked_mul(stride).and_then(|b| b.checked_add(accessor.offset() + element)),
        };
        let data = &buffer[view.offset()..view_end];
        match needed {
            Some(needed) if needed <= data.len() => Ok(Some((&data[accessor.offset()..], stride, element))),
            _ => Err(self.error(format!(
                "{what}: accessor {index} ({count} elements) runs past the end of buffer view {} ({} bytes)",
                view.index(),
                view.length()
            ))),
        }
    }

    /// An accessor of N-component float vectors (f32, or normalised integers as
    /// `KHR_mesh_quantization` allows), every value finite.
    pub(super) fn read_vectors<const N: usize>(
        &self,
        accessor: &::gltf::Accessor,
        what: &str,
    ) -> Result<Vec<[f32; N]>> {
        let dimensions = accessor.dimensions();
        if dimensions.multiplicity() != N || matches!(dimensions, Dimensions::Mat2) {
            return Err(
                self.error(format!("{what}: accessor {} is {dimensions:?}, expected {N} components", accessor.index()))
            );
        }
        let data_type = accessor.data_type();
        let normalized = accessor.normalized();
        if data_type == DataType::U32 || (data_type != DataType::F32 && !normalized && N != 3) {
            let message =
                format!("{what}: accessor {} has {data_type:?} components, not float or normalised", accessor.index());
            return Err(self.error(message));
        }
        let count = accessor.count();
        let Some((data, stride, _)) = self.accessor_bytes(accessor, what)? else {
            return Ok(vec![[0.0; N]; count]);
        };
        let size = data_type.size();
        let mut out = Vec::with_capacity(count);
        for k in 0..count {
            let mut v = [0.0f32; N];
            for (j, c) in v.iter_mut().enumerate() {
                let at = k * stride + j * size;
                *c = component(&data[at..at + size], data_type, normalized);
            }
            if !v.iter().all(|c| c.is_finite()) {
                return Err(
                    self.error(format!("{what}: accessor {} element {k} is not finite ({v:?})", accessor.index()))
                );
            }
            out.push(v);
        }
        Ok(out)
    }

    /// An index accessor (scalar u8, u16 or u32), every index below `vertices`.
    pub(super) fn read_indices(&self, accessor: &::gltf::Accessor, vertices: usize, what: &str) -> Result<Vec<u32>> {
        let data_type = accessor.data_type();
        if accessor.dimensions() != Dimensions::Scalar
            || !matches!(data_type, DataType::U8 | DataType::U16 | DataType::U32)
        {
            return Err(self.error(format!(
                "{what}: accessor {} is {:?} {data_type:?}, expected unsigned scalar indices",
                accessor.index(),
                accessor.dimensions()
            )));
        }
        let count = accessor.count();
        let Some((data, stride, size)) = self.accessor_bytes(accessor, what)? else {
            return Ok(vec![0; count]);
        };
        let mut out = Vec::with_capacity(count);
        for k in 0..count {
            let b = &data[k * stride..k * stride + size];
            let index = match data_type {
                DataType::U8 => b[0] as u32,
                DataType::U16 => u16::from_le_bytes([b[0], b[1]]) as u32,
                _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
            };
            if index as usize >= vertices {
                return Err(self.error(format!("{what}: index {index} at {k} is out of range ({vertices} vertices)")));
            }
            out.push(index);
        }
        Ok(out)
    }

    /// A scalar float accessor (animation times).
    pub(super) fn read_scalars(&self, accessor: &::gltf::Accessor, what: &str) -> Result<Vec<f64>> {
        Ok(self.read_vectors::<1>(accessor, what)?.into_iter().map(|[t]| t as f64).collect())
    }
}

/// One component, converted as glTF's normalised integers are (signed: max(c / MAX, −1)).
fn component(b: &[u8], data_type: DataType, normalized: bool) -> f32 {
    match (data_type, normalized) {
        (DataType::F32, _) => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
        (DataType::U8, true) => b[0] as f32 / 255.0,
        (DataType::U8, false) => b[0] as f32,
        (DataType::I8, true) => (b[0] as i8 as f32 / 127.0).max(-1.0),
        (DataType::I8, false) => b[0] as i8 as f32,
        (DataType::U16, true) => u16::from_le_bytes([b[0], b[1]]) as f32 / 65535.0,
        (DataType::U16, false) => u16::from_le_bytes([b[0], b[1]]) as f32,
        (DataType::I16, true) => (i16::from_le_bytes([b[0], b[1]]) as f32 / 32767.0).max(-1.0),
        (DataType::I16, false) => i16::from_le_bytes([b[0], b[1]]) as f32,
        (DataType::U32, _) => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32,
    }
}
