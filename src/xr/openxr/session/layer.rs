//! xrEndFrame with the frame's projection layer (and each view's depth when the
//! swapchains carry it), or with no layer.

use super::*;

/// The projection layer of one frame.
pub(super) struct Layer {
    pub(super) views: [xr::View; 2],
    pub(super) sub_images: [SubImage; 2],
    pub(super) near: f64,
}

/// xrEndFrame with the projection layer (and per-view depth when the swapchains have
/// it), or with no layer.
pub(super) fn end_frame(
    xr: &mut Xr,
    display_time: xr::Time,
    layer: Option<&Layer>,
) -> std::result::Result<(), xr::sys::Result> {
    use xr::sys;
    let rect = |s: &SubImage| sys::Rect2Di {
        offset: sys::Offset2Di { x: 0, y: 0 },
        extent: sys::Extent2Di { width: s.width as i32, height: s.height as i32 },
    };
    let mut depth_infos = [None, None];
    let mut projection_views = Vec::with_capacity(2);
    let projection;
    let mut layers: Vec<*const sys::CompositionLayerBaseHeader> = Vec::new();
    if let Some(layer) = layer {
        for (eye, depth_info) in depth_infos.iter_mut().enumerate() {
            let s = &layer.sub_images[eye];
            if let Some(depth) = xr.swapchains.depth_swapchain(s.swapchain) {
                // Reversed-Z with an infinite far plane: window depth 0 is infinitely
                // far and 1 is the near plane. The extension's nearZ and farZ are the
                // distances of minDepth and maxDepth ("a nearZ greater than farZ means
                // reversed depth"), so minDepth 0 ↔ nearZ = far and maxDepth 1 ↔ farZ =
                // the near plane. nearZ is f32::MAX, not +∞: a runtime linearising depth
                // with ∞ gets NaN (∞/∞, ∞·0), and no depth value tells the two apart.
                *depth_info = Some(sys::CompositionLayerDepthInfoKHR {
                    ty: sys::CompositionLayerDepthInfoKHR::TYPE,
                    next: std::ptr::null(),
                    sub_image: sys::SwapchainSubImage {
                        swapchain: depth.as_raw(),
                        image_rect: rect(s),
                        image_array_index: s.array_index,
                    },
                    min_depth: 0.0,
                    max_depth: 1.0,
                    near_z: f32::MAX,
                    far_z: layer.near as f32,
                });
            }
        }
        for (eye, view) in layer.views.iter().enumerate() {
            let s = &layer.sub_images[eye];
            projection_views.push(sys::CompositionLayerProjectionView {
                ty: sys::CompositionLayerProjectionView::TYPE,
                next: depth_infos[eye].as_ref().map_or(std::ptr::null(), |d| d as *const _ as *const _),
                pose: view.pose,
                fov: view.fov,
                sub_image: sys::SwapchainSubImage {
                    swapchain: xr.swapchains.color_swapchain(s.swapchain).as_raw(),
                    image_rect: rect(s),
                    image_array_index: s.array_index,
                },
            });
        }
        projection = sys::CompositionLayerProjection {
            ty: sys::CompositionLayerProjection::TYPE,
            next: std::ptr::null(),
            layer_flags: sys::CompositionLayerFlags::EMPTY,
            space: xr.space.as_raw(),
            view_count: projection_views.len() as u32,
            views: projection_views.as_ptr(),
        };
        layers.push(&projection as *const _ as *const sys::CompositionLayerBaseHeader);
    }
    let info = sys::FrameEndInfo {
        ty: sys::FrameEndInfo::TYPE,
        next: std::ptr::null(),
        display_time,
        environment_blend_mode: xr.blend_mode,
        layer_count: layers.len() as u32,
        layers: if layers.is_empty() { std::ptr::null() } else { layers.as_ptr() },
    };
    // SAFETY: every pointer in `info` (layers, views, depth infos) points at locals that
    // live until the call returns; the frame was begun with xrBeginFrame.
    let result = unsafe { (xr.instance.fp().end_frame)(xr.session.as_raw(), &info) };
    if result.into_raw() < 0 {
        Err(result)
    } else {
        Ok(())
    }
}
