//! Accessors decoded by hand: every byte range checked against its buffer view and
//! buffer, in checked arithmetic, before it is read (the crate's readers assume valid
//! ranges). A sparse accessor (glTF 2.0 §3.6.2.3) is its base (its buffer view, or zeros
//! without one) with `sparse.count` elements replaced; it goes through the same readers
//! as a dense one. The component types each use of an accessor may have are one table
//! ([`Use::integers`]): glTF 2.0's, widened for mesh attributes by `KHR_mesh_quantization`.

use super::{Loader, MAX_ACCESSOR_COUNT, MAX_VERTICES};
use ::gltf::accessor::{DataType, Dimensions};
use vrao_ao::Result;

/// What an accessor holds, which decides the component types glTF allows for it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Use {
    /// `POSITION` (VEC3).
    Position,
    /// `NORMAL` (VEC3).
    Normal,
    /// `TANGENT` (VEC4).
    Tangent,
    /// `TEXCOORD_n` (VEC2).
    TexCoord,
    /// `COLOR_n` (VEC3 or VEC4).
    Color,
    /// An animation sampler's input: key times (SCALAR).
    KeyTimes,
    /// An animation sampler's translation or scale output (VEC3).
    KeyVectors,
    /// An animation sampler's rotation output (VEC4).
    Rotation,
}

impl Use {
    /// The integer component types allowed beside float: (as normalised values, as plain
    /// values). glTF 2.0 §3.7.2.1 and §3.11 for colours and animations;
    /// `KHR_mesh_quantization` for positions, normals, tangents and texture coordinates.
    pub(super) fn integers(self) -> (&'static [DataType], &'static [DataType]) {
        use DataType::{I16, I8, U16, U8};
        const ANY: &[DataType] = &[I8, U8, I16, U16];
        const SIGNED: &[DataType] = &[I8, I16];
        const UNSIGNED: &[DataType] = &[U8, U16];
        match self {
            Use::Position | Use::TexCoord => (ANY, ANY),
            Use::Normal | Use::Tangent => (SIGNED, &[]),
            Use::Color => (UNSIGNED, &[]),
            Use::Rotation => (ANY, &[]),
            Use::KeyTimes | Use::KeyVectors => (&[], &[]),
        }
    }

    /// Whether glTF allows `data_type` (normalised or not) for this use.
    fn allows(self, data_type: DataType, normalized: bool) -> bool {
        let (normalised, plain) = self.integers();
        data_type == DataType::F32 || if normalized { normalised } else { plain }.contains(&data_type)
    }

    /// The accessor types allowed for this use.
    fn dimensions(self) -> &'static [Dimensions] {
        match self {
            Use::Position | Use::Normal | Use::KeyVectors => &[Dimensions::Vec3],
            Use::Tangent | Use::Rotation => &[Dimensions::Vec4],
            Use::TexCoord => &[Dimensions::Vec2],
            Use::Color => &[Dimensions::Vec3, Dimensions::Vec4],
            Use::KeyTimes => &[Dimensions::Scalar],
        }
    }

    fn name(self) -> &'static str {
        match self {
            Use::Position => "POSITION",
            Use::Normal => "NORMAL",
            Use::Tangent => "TANGENT",
            Use::TexCoord => "TEXCOORD_n",
            Use::Color => "COLOR_n",
            Use::KeyTimes => "an animation input",
            Use::KeyVectors => "a translation or scale output",
            Use::Rotation => "a rotation output",
        }
    }

    /// What the table allows, in words ("f32, normalised i8 or i16").
    fn allowed(self) -> String {
        let list = |types: &[DataType]| types.iter().map(|&t| type_name(t)).collect::<Vec<_>>().join(", ");
        let (normalised, plain) = self.integers();
        let mut parts = vec!["f32".to_string()];
        match (normalised.is_empty(), plain.is_empty()) {
            (true, _) => {}
            (false, true) => parts.push(format!("normalised {}", list(normalised))),
            (false, false) if normalised == plain => parts.push(format!("{} (normalised or not)", list(normalised))),
            (false, false) => {
                parts.push(format!("normalised {}", list(normalised)));
                parts.push(list(plain));
            }
        }
        let mut text = parts.join("; ");
        if matches!(self, Use::Position | Use::Normal | Use::Tangent | Use::TexCoord) {
            text.push_str(" (KHR_mesh_quantization)");
        }
        text
    }
}

/// Short names of component types, as messages give them.
fn type_name(data_type: DataType) -> &'static str {
    match data_type {
        DataType::I8 => "i8",
        DataType::U8 => "u8",
        DataType::I16 => "i16",
        DataType::U16 => "u16",
        DataType::U32 => "u32",
        DataType::F32 => "f32",
    }
}

/// Zero bytes for the elements of an accessor without a buffer view (the largest element,
/// a MAT4 of f32, has 64 bytes).
const ZEROS: [u8; 64] = [0; 64];

/// An accessor's elements once every range is checked: the base (a strided run of its
/// buffer view, or zeros) with the sparse substitutions, if any, over it.
pub(super) struct Elements<'b> {
    count: usize,
    /// Bytes per element.
    size: usize,
    /// The base's bytes from its first element, and its stride; `None` for zeros.
    base: Option<(&'b [u8], usize)>,
    /// Substituted elements, strictly increasing, each below `count`.
    indices: Vec<u32>,
    /// Their values, `size` bytes each, tightly packed.
    values: &'b [u8],
}

impl Elements<'_> {
    /// How many elements the accessor has.
    pub(super) fn len(&self) -> usize {
        self.count
    }

    /// Every element's bytes, in order.
    pub(super) fn iter(&self) -> impl Iterator<Item = &[u8]> + '_ {
        let mut next = 0;
        (0..self.count).map(move |k| {
            if self.indices.get(next).is_some_and(|&i| i as usize == k) {
                next += 1;
                &self.values[(next - 1) * self.size..next * self.size]
            } else {
                match self.base {
                    Some((data, stride)) => &data[k * stride..k * stride + self.size],
                    None => &ZEROS[..self.size],
                }
            }
        })
    }
}

impl Loader<'_> {
    /// A buffer view's bytes, checked against its buffer.
    pub(super) fn view_bytes(&self, view: &::gltf::buffer::View, what: &str) -> Result<&[u8]> {
        let buffer = &self.buffers[view.buffer().index()];
        match view.offset().checked_add(view.length()).filter(|&end| end <= buffer.len()) {
            Some(end) => Ok(&buffer[view.offset()..end]),
            None => Err(self.error(format!(
                "{what}: buffer view {} (bytes {}..+{}) runs past the end of buffer {} ({} bytes)",
                view.index(),
                view.offset(),
                view.length(),
                view.buffer().index(),
                buffer.len()
            ))),
        }
    }

    /// The elements an accessor reads, every range checked against its views and buffers:
    /// the dense base and, for a sparse accessor, its indices (u8, u16 or u32, strictly
    /// increasing, each below the count) and values.
    pub(super) fn elements(&self, accessor: &::gltf::Accessor, what: &str) -> Result<Elements<'_>> {
        let index = accessor.index();
        let count = accessor.count();
        if count > MAX_ACCESSOR_COUNT {
            return Err(self.error(format!(
                "{what}: accessor {index} declares {count} elements (vrao's limit: {MAX_ACCESSOR_COUNT})"
            )));
        }
        // At most 16 components of 4 bytes: no overflow.
        let size = accessor.dimensions().multiplicity() * accessor.data_type().size();
        let base = self.dense_base(accessor, size, what)?;
        let mut elements = Elements { count, size, base, indices: Vec::new(), values: &[] };
        let Some(sparse) = accessor.sparse() else { return Ok(elements) };
        let substituted = sparse.count();
        if substituted > count {
            return Err(self.error(format!(
                "{what}: accessor {index} replaces {substituted} elements (sparse.count) of its {count}"
            )));
        }
        let packed = |view: ::gltf::buffer::View, offset: usize, element: usize, part: &str| -> Result<&[u8]> {
            let data = self.view_bytes(&view, what)?;
            let end = substituted.checked_mul(element).and_then(|b| b.checked_add(offset));
            match end {
                Some(end) if end <= data.len() => Ok(&data[offset..end]),
                _ => Err(self.error(format!(
                    "{what}: accessor {index} sparse {part} ({substituted} × {element} bytes from byte {offset}) run past the end of buffer view {} ({} bytes)",
                    view.index(),
                    view.length()
                ))),
            }
        };
        let indices = sparse.indices();
        // The crate's validation leaves only u8, u16 and u32 here.
        let index_size = indices.index_type().size();
        let index_bytes = packed(indices.view(), indices.offset(), index_size, "indices")?;
        elements.values = packed(sparse.values().view(), sparse.values().offset(), size, "values")?;
        elements.indices = self.sparse_indices(index_bytes, index_size, count, index, what)?;
        Ok(elements)
    }

    /// The dense base of an accessor of `size`-byte elements: its buffer view's bytes from
    /// the accessor's offset and its stride, every element in range, or `None` (zeros)
    /// without a view.
    fn dense_base(&self, accessor: &::gltf::Accessor, size: usize, what: &str) -> Result<Option<(&[u8], usize)>> {
        let index = accessor.index();
        let count = accessor.count();
        let Some(view) = accessor.view() else {
            // Zeros cost the file nothing: a few bytes of JSON must not make gigabytes.
            if count > MAX_VERTICES {
                return Err(self.error(format!(
                    "{what}: accessor {index} declares {count} elements without a buffer view (vrao's limit for those: {MAX_VERTICES})"
                )));
            }
            return Ok(None);
        };
        let data = self.view_bytes(&view, what)?;
        let stride = view.stride().unwrap_or(size);
        if stride < size {
            return Err(
                self.error(format!("{what}: accessor {index} stride {stride} is less than its element size {size}"))
            );
        }
        let offset = accessor.offset();
        let end = match count {
            0 => Some(offset),
            n => (n - 1).checked_mul(stride).and_then(|b| b.checked_add(size)).and_then(|b| b.checked_add(offset)),
        };
        match end {
            Some(end) if end <= data.len() => Ok(Some((&data[offset..], stride))),
            _ => {
                let at = if offset == 0 { String::new() } else { format!(" from byteOffset {offset}") };
                Err(self.error(format!(
                    "{what}: accessor {index} ({count} elements) runs past the end of buffer view {} ({} bytes){at}",
                    view.index(),
                    view.length()
                )))
            }
        }
    }

    /// A sparse accessor's indices from their packed little-endian `index_size`-byte
    /// integers: each below `count` (the elements of accessor `index`) and strictly
    /// increasing, so the substitutions apply in one pass.
    fn sparse_indices(
        &self,
        index_bytes: &[u8],
        index_size: usize,
        count: usize,
        index: usize,
        what: &str,
    ) -> Result<Vec<u32>> {
        let mut indices: Vec<u32> = Vec::with_capacity(index_bytes.len() / index_size);
        for (k, b) in index_bytes.chunks_exact(index_size).enumerate() {
            let i = match index_size {
                1 => b[0] as u32,
                2 => u16::from_le_bytes([b[0], b[1]]) as u32,
                _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
            };
            if i as usize >= count {
                return Err(self.error(format!(
                    "{what}: accessor {index} sparse index {i} (at {k}) is out of range ({count} elements)"
                )));
            }
            if let Some(&last) = indices.last() {
                if i <= last {
                    return Err(self.error(format!(
                        "{what}: accessor {index} sparse indices {last} then {i} (at {k}) are not strictly increasing"
                    )));
                }
            }
            indices.push(i);
        }
        Ok(indices)
    }

    /// An accessor of N-component vectors for `usage`: float, or the integers glTF allows
    /// for that use ([`Use::integers`]), every value finite.
    pub(super) fn read_as<const N: usize>(
        &self,
        accessor: &::gltf::Accessor,
        usage: Use,
        what: &str,
    ) -> Result<Vec<[f32; N]>> {
        let index = accessor.index();
        let dimensions = accessor.dimensions();
        if dimensions.multiplicity() != N || matches!(dimensions, Dimensions::Mat2) {
            return Err(self.error(format!("{what}: accessor {index} is {dimensions:?}, expected {N} components")));
        }
        let allowed = usage.dimensions();
        if !allowed.contains(&dimensions) {
            let names: Vec<String> = allowed.iter().map(|d| format!("{d:?}").to_uppercase()).collect();
            return Err(self.error(format!(
                "{what}: accessor {index} is {}, {} takes {}",
                format!("{dimensions:?}").to_uppercase(),
                usage.name(),
                names.join(" or ")
            )));
        }
        let data_type = accessor.data_type();
        let normalized = accessor.normalized() && data_type != DataType::F32;
        if !usage.allows(data_type, normalized) {
            let kind = if normalized { "normalised" } else { "unnormalised" };
            return Err(self.error(format!(
                "{what}: accessor {index} has {kind} {} components; {} takes {}",
                type_name(data_type),
                usage.name(),
                usage.allowed()
            )));
        }
        let elements = self.elements(accessor, what)?;
        let size = data_type.size();
        let mut out = Vec::with_capacity(elements.len());
        for (k, bytes) in elements.iter().enumerate() {
            let mut v = [0.0f32; N];
            for (j, c) in v.iter_mut().enumerate() {
                *c = component(&bytes[j * size..(j + 1) * size], data_type, normalized);
            }
            if !v.iter().all(|c| c.is_finite()) {
                return Err(self.error(format!("{what}: accessor {index} element {k} is not finite ({v:?})")));
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
        let elements = self.elements(accessor, what)?;
        let mut out = Vec::with_capacity(elements.len());
        for (k, b) in elements.iter().enumerate() {
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
        Ok(self.read_as::<1>(accessor, Use::KeyTimes, what)?.into_iter().map(|[t]| t as f64).collect())
    }
}

/// One component, converted as glTF's normalised integers are (signed: max(c / MAX, −1))
/// or as its value when not normalised.
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
