//! The runtime calls behind the session's visibility mask (XR_KHR_visibility_mask): each
//! view's mesh through `xrGetVisibilityMaskKHR`'s two-call idiom, with the counts
//! bounded before anything is allocated. What is done with the meshes is
//! `openxr/mask.rs`'s.

use super::*;
use crate::xr::openxr::mask::{check_counts, skip_runtime_mask, view_mask, MaskChoice, MaskMesh, SessionMask, VIEWS};
use vrao_ao::ViewMask;
use vrao_render::scene::limits::Trouble;

/// How often the two-call idiom is tried again when the mask grows between its calls.
const READ_TRIES: usize = 3;

/// The session's mask at its start: read from the runtime for every view when the
/// extension is enabled (a view without one is logged and leaves the session without a
/// mask), else, or where vrao does not call it (`skip_runtime_mask`), Monado's default
/// from the fields of view of the frames.
pub(super) fn initial(session: &xr::Session<xr::Vulkan>, enabled: bool) -> SessionMask {
    // `vrao run` refuses a bad value before any session opens; a caller that did not
    // check gets vrao's own choice, said once.
    let choice = MaskChoice::from_env().unwrap_or_else(|e| {
        log::warn!("OpenXR: {e}: not used");
        None
    });
    let skipped = match session.instance().properties() {
        Ok(props) => skip_runtime_mask(&props.runtime_name, props.runtime_version.major(), choice),
        Err(_) => None,
    };
    let why = match (enabled, skipped) {
        (false, _) => "the OpenXR runtime offers no XR_KHR_visibility_mask".to_string(),
        (true, Some(why)) => why,
        (true, None) => String::new(),
    };
    if !why.is_empty() {
        log::info!("OpenXR: visibility mask: Monado's default from each view's field of view ({why})");
        return SessionMask::from_field_of_view(&why);
    }
    let reads: [std::result::Result<ViewMask, Trouble>; VIEWS] = std::array::from_fn(|i| read_view(session, i as u32));
    let (mask, problem) = SessionMask::from_runtime(reads);
    if let Some(problem) = problem {
        log::warn!("OpenXR: {problem}");
    }
    mask
}

/// One view's mask: its hidden triangle mesh, else (when that is empty) its visible one.
pub(super) fn read_view(session: &xr::Session<xr::Vulkan>, view: u32) -> std::result::Result<ViewMask, Trouble> {
    view_mask(read_mesh(session, view, xr::VisibilityMaskTypeKHR::HIDDEN_TRIANGLE_MESH), || {
        read_mesh(session, view, xr::VisibilityMaskTypeKHR::VISIBLE_TRIANGLE_MESH)
    })
}

/// `xrGetVisibilityMaskKHR` for one view and mesh type: the counts first, then the
/// buffers (again with the new counts when the runtime answers SIZE_INSUFFICIENT, the
/// mask having changed in between). Counts above `MAX_MESH_ELEMENTS` are refused.
fn read_mesh(
    session: &xr::Session<xr::Vulkan>,
    view: u32,
    kind: xr::VisibilityMaskTypeKHR,
) -> std::result::Result<MaskMesh, Trouble> {
    const CALL: &str = "xrGetVisibilityMaskKHR";
    let Some(ext) = session.instance().exts().khr_visibility_mask.as_ref() else {
        return Err("XR_KHR_visibility_mask is not enabled".into());
    };
    let mut info = xr::sys::VisibilityMaskKHR {
        ty: xr::sys::VisibilityMaskKHR::TYPE,
        next: std::ptr::null_mut(),
        vertex_capacity_input: 0,
        vertex_count_output: 0,
        vertices: std::ptr::null_mut(),
        index_capacity_input: 0,
        index_count_output: 0,
        indices: std::ptr::null_mut(),
    };
    // SAFETY: the function pointer was loaded for this session's instance; with both
    // capacities 0 the runtime only writes the two counts into `info`.
    let result = unsafe { (ext.get_visibility_mask)(session.as_raw(), VIEW_TYPE, view, kind, &mut info) };
    if result.into_raw() < 0 {
        return Err(super::super::xr_call_failed(CALL, result).into());
    }
    for _ in 0..READ_TRIES {
        check_counts(info.vertex_count_output, info.index_count_output)?;
        if info.vertex_count_output == 0 || info.index_count_output == 0 {
            return Ok(MaskMesh::default());
        }
        let mut vertices = vec![xr::Vector2f::default(); info.vertex_count_output as usize];
        let mut indices = vec![0u32; info.index_count_output as usize];
        info.vertex_capacity_input = vertices.len() as u32;
        info.vertices = vertices.as_mut_ptr();
        info.index_capacity_input = indices.len() as u32;
        info.indices = indices.as_mut_ptr();
        // SAFETY: `vertices` and `indices` hold the capacities `info` states and outlive
        // the call; the runtime writes at most that many of each.
        let result = unsafe { (ext.get_visibility_mask)(session.as_raw(), VIEW_TYPE, view, kind, &mut info) };
        info.vertices = std::ptr::null_mut();
        info.indices = std::ptr::null_mut();
        if result == xr::sys::Result::ERROR_SIZE_INSUFFICIENT {
            continue;
        }
        if result.into_raw() < 0 {
            return Err(super::super::xr_call_failed(CALL, result).into());
        }
        vertices.truncate(info.vertex_count_output as usize);
        indices.truncate(info.index_count_output as usize);
        return Ok(MaskMesh { vertices: vertices.iter().map(|v| glam::Vec2::new(v.x, v.y)).collect(), indices });
    }
    Err(format!("{CALL}: the mask kept growing between the count and the read ({READ_TRIES} tries)").into())
}
