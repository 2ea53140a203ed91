//! Test helper: checks each `#[repr(C)]` struct that mirrors a WGSL struct against that
//! struct as naga lays it out (`naga::proc::Layouter`), from the WGSL files its pipeline
//! compiles, in the same order. vrao-ao's tests use it as `gpu::layout_check`; the crates
//! that depend on vrao-ao turn on its `layout-check` feature for their tests (their
//! dev-dependency); the embed example includes this file. Each keeps one [`mirror!`] line
//! per mirror:
//!
//! ```text
//! use crate::gpu::layout_check::{self, mirror};
//! layout_check::check(&[
//!     mirror!(GtaoUniform, GTAO_FILES, "GtaoParams", [slices, steps, thickness, step_power, connect, inner_band]),
//! ]);
//! ```
//!
//! The Rust fields are listed by hand (`offset_of!` needs their names) without the
//! padding; both sides' padding members (named `pad…` or `_pad…`) are skipped. The
//! remaining members are compared in order by offset and size (names may differ; a
//! failure names both), and the structs by size: a WGSL struct's size is already a
//! multiple of its alignment, so equal sizes also keep the Rust size aligned.

#![allow(dead_code, unreachable_pub)]

/// One Rust field of a mirror.
pub struct Field {
    /// Its name.
    pub name: &'static str,
    /// `offset_of!`.
    pub offset: usize,
    /// Its type's size.
    pub size: usize,
}

/// WGSL text that is no file of a `Shader` (a constant in Rust code): what [`mirror!`]
/// takes in a file list besides the crates' `Shader`s (both have `path` and `source`).
pub struct Text {
    /// Where it is, for messages.
    pub path: &'static str,
    /// The WGSL.
    pub source: &'static str,
}

/// A Rust struct and the WGSL struct it mirrors.
pub struct Mirror {
    /// The Rust type's name.
    pub rust: &'static str,
    /// `size_of` the Rust type.
    pub size: usize,
    /// The listed Rust fields, in declaration order.
    pub fields: Vec<Field>,
    /// The WGSL files the pipeline compiles, in order: (path, text).
    pub files: Vec<(&'static str, &'static str)>,
    /// The WGSL struct's name.
    pub wgsl: &'static str,
}

/// The size of the field `field` picks (`|s: &T| &s.field`).
pub fn field_size<T, F>(_field: impl Fn(&T) -> &F) -> usize {
    std::mem::size_of::<F>()
}

/// `mirror!(RustType, files, "WgslStruct", [field, …])`: one [`Mirror`]. `files` is what
/// the pipeline compiles: an array or slice of `Shader`s (or [`Text`]s), in its order.
/// The caller has this module in scope as `layout_check`.
#[macro_export]
#[doc(hidden)]
macro_rules! layout_check_mirror {
    ($ty:ty, $files:expr, $wgsl:literal, [$($field:ident),+ $(,)?]) => {
        layout_check::Mirror {
            rust: stringify!($ty),
            size: ::std::mem::size_of::<$ty>(),
            fields: vec![$(layout_check::Field {
                name: stringify!($field),
                offset: ::std::mem::offset_of!($ty, $field),
                size: layout_check::field_size(|s: &$ty| &s.$field),
            }),+],
            files: $files.iter().map(|f| (f.path, f.source)).collect(),
            wgsl: $wgsl,
        }
    };
}
pub use crate::layout_check_mirror as mirror;

/// Whether a member is padding (skipped on both sides).
fn is_padding(name: &str) -> bool {
    name.starts_with("pad") || name.starts_with("_pad")
}

/// A WGSL member as laid out: name, offset, size.
struct Member {
    name: String,
    offset: u32,
    size: u32,
}

/// The WGSL struct `name` of `source` as naga lays it out: (size, alignment, members).
fn wgsl_layout(source: &str, name: &str) -> Result<(u32, u32, Vec<Member>), String> {
    let module = naga::front::wgsl::parse_str(source).map_err(|e| e.emit_to_string(source))?;
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(module.to_ctx()).map_err(|e| format!("naga's layouter: {e}"))?;
    let mut found = module.types.iter().filter(|(_, ty)| ty.name.as_deref() == Some(name));
    let Some((handle, ty)) = found.next() else {
        return Err(format!("no struct `{name}` in the WGSL"));
    };
    let naga::TypeInner::Struct { members, .. } = &ty.inner else {
        return Err(format!("`{name}` is no struct"));
    };
    let members = members
        .iter()
        .map(|m| Member { name: m.name.clone().unwrap_or_default(), offset: m.offset, size: layouter[m.ty].size })
        .collect();
    let layout = &layouter[handle];
    Ok((layout.size, layout.alignment.round_up(1), members))
}

/// The differences between `mirror` and its WGSL struct, one line each.
pub fn differences(mirror: &Mirror) -> Vec<String> {
    // The pipeline's composition (`Kernel::in_chain` without a shader directory): the
    // chain's prelude (its layouts declare no struct), then each file's text and a
    // newline, in order.
    // (Read here, not through `kernel`: the embed example's tests include this file alone.)
    let prelude = include_str!("../../shaders/chain_rgba.wgsl");
    let source: String =
        std::iter::once(prelude).chain(mirror.files.iter().map(|(_, text)| *text)).map(|t| format!("{t}\n")).collect();
    let paths: Vec<&str> = mirror.files.iter().map(|(path, _)| *path).collect();
    let here = format!("{} vs `{}` of [{}]", mirror.rust, mirror.wgsl, paths.join(", "));
    let (size, align, members) = match wgsl_layout(&source, mirror.wgsl) {
        Ok(layout) => layout,
        Err(e) => return vec![format!("{here}: {e}")],
    };
    let mut out = Vec::new();
    if mirror.size != size as usize {
        out.push(format!("{here}: size {} in Rust, {size} in WGSL", mirror.size));
    }
    if !mirror.size.is_multiple_of(align as usize) {
        out.push(format!("{here}: Rust size {} is not a multiple of the WGSL alignment {align}", mirror.size));
    }
    let wgsl: Vec<&Member> = members.iter().filter(|m| !is_padding(&m.name)).collect();
    let rust: Vec<&Field> = mirror.fields.iter().filter(|f| !is_padding(f.name)).collect();
    for i in 0..rust.len().max(wgsl.len()) {
        let describe_rust = |f: Option<&&Field>| {
            f.map_or("nothing".into(), |f| format!("`{}` at {} ({} bytes)", f.name, f.offset, f.size))
        };
        let describe_wgsl = |m: Option<&&Member>| {
            m.map_or("nothing".into(), |m| format!("`{}` at {} ({} bytes)", m.name, m.offset, m.size))
        };
        let (r, w) = (rust.get(i), wgsl.get(i));
        let same = matches!((r, w), (Some(r), Some(w)) if r.offset == w.offset as usize && r.size == w.size as usize);
        if !same {
            out.push(format!("{here}: member {i}: Rust {}, WGSL {}", describe_rust(r), describe_wgsl(w)));
        }
    }
    out
}

/// Panics with every difference of every mirror, one line each.
pub fn check(mirrors: &[Mirror]) {
    let lines: Vec<String> = mirrors.iter().flat_map(differences).collect();
    assert!(lines.is_empty(), "Rust mirrors differ from their WGSL structs:\n{}", lines.join("\n"));
}
