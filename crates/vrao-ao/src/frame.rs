//! What a frame's passes are declared with: the chain's settings, each view and its
//! motion, the renderer's extensions. A leaf below the frame graph and the passes, which
//! both read it.

use crate::settings::AoSettings;
use std::any::Any;

/// What the AO chain's passes read of the settings: each view's size, the near plane and
/// the AO settings. A renderer's own settings reach its passes as an extension
/// ([`DeclareContext::extension`]).
#[derive(Clone, Debug, PartialEq)]
pub struct ChainSettings {
    /// Width of each view in pixels (full resolution).
    pub width: u32,
    /// Height of each view in pixels.
    pub height: u32,
    /// Near plane distance (reversed-Z, far plane at infinity).
    pub near: f64,
    /// The AO settings.
    pub ao: AoSettings,
}

/// What passes may consult when declaring themselves for a frame.
pub struct DeclareContext<'a> {
    /// What a renderer's own passes read beyond the engine's (its scene, its uploaded
    /// scene, its settings), found by type ([`DeclareContext::extension`]); empty in the AO
    /// engine.
    pub extensions: &'a [&'a dyn Any],
    /// Whether the normals' w marks alpha-tested surfaces (cards) that GTAO samples as
    /// thin planes (a renderer's scene with alpha-tested materials; never a host's).
    pub alpha_cards: bool,
    /// Whether a second depth layer ([`DEPTH_LAYER_2`](crate::plug::DEPTH_LAYER_2)) can be
    /// had: a renderer peels one (its scene can have a surface behind another) or a host
    /// gave one. False: the occlusion reads one layer whatever the settings' `layers`.
    pub second_layer: bool,
    /// The f64 origin that view-from-anchored matrices start from (the scene's anchor;
    /// the world origin for a host's views).
    pub anchor: glam::DVec3,
    /// This frame's settings.
    pub settings: &'a ChainSettings,
    /// 2 for stereo, 1 for a mono view.
    pub views: u32,
    /// Whether the G-buffer draws both layers in one multiview pass.
    pub multiview: bool,
    /// Frames this renderer has rendered before this one (turns sampling patterns).
    pub frame_index: u64,
    /// This frame's views (empty when only planning).
    pub current_views: &'a [crate::stereo::Eye],
    /// The previous frame's views, when it had as many as this one (temporal reuse).
    pub previous_views: Option<&'a [crate::stereo::Eye]>,
    /// What moves this frame ([`FrameMotion::STILL`] in a still scene).
    pub motion: &'a FrameMotion,
    /// How the AO chain's targets hold a texel this frame: AO alone where the technique
    /// carries no light and the device writes `R16Float` storage, else rgb light and AO.
    pub chain: crate::resource::ChainLayout,
}

/// What moved since the previous frame, for temporal accumulation.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameMotion {
    /// Whether [`MOTION`](crate::plug::MOTION) holds each pixel's motion this frame (the scene
    /// moves, or a host handed its motion vectors to the AO engine).
    pub vectors: bool,
    /// Boxes around every moving object, where it is and where it was in the previous
    /// frame: the AO of what lies within the AO radius of them changes although the
    /// surface itself does not move.
    pub movers: Vec<MoverBox>,
    /// What turns a motion texel's xy into the uv offset to the previous frame
    /// (1, 1 for the G-buffer's).
    pub uv_scale: [f32; 2],
    /// Whether the motion's z holds the change in distance and w its validity (the
    /// G-buffer's); a host's 2D vectors leave the distance to the eyes' motion.
    pub with_distance: bool,
}

/// An oriented box around a moving object (`MoverBox` of temporal.wgsl): a point p of
/// the anchored frame lies inside when |rows · (p, 1)| ≤ half_extents on each axis.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct MoverBox {
    /// The box's frame from the anchored world frame: three rows of an affine map whose
    /// rotation is orthonormal, so distances stay in metres.
    pub box_from_anchored: [[f32; 4]; 3],
    /// Half the box's size along its axes (metres); w unused.
    pub half_extents: [f32; 4],
}

impl MoverBox {
    /// The box `local` (min and max corners in a node's frame) placed by `world` (world from local,
    /// rotation and scale without shear), relative to `anchor`.
    pub fn of(local: (glam::DVec3, glam::DVec3), world: &glam::DMat4, anchor: glam::DVec3) -> MoverBox {
        let (min, max) = local;
        let m = glam::DMat3::from_mat4(*world);
        let axes = [m.x_axis, m.y_axis, m.z_axis];
        let half = (max - min) * 0.5;
        let centre = world.transform_point3((min + max) * 0.5) - anchor;
        let mut rows = [[0.0f32; 4]; 3];
        let mut half_extents = [0.0f32; 4];
        for (i, axis) in axes.iter().enumerate() {
            let length = axis.length();
            let unit = if length > 0.0 && length.is_finite() { *axis / length } else { glam::DVec3::ZERO };
            rows[i] = [unit.x as f32, unit.y as f32, unit.z as f32, -unit.dot(centre) as f32];
            half_extents[i] = (half[i] * length) as f32;
        }
        MoverBox { box_from_anchored: rows, half_extents }
    }
}

impl FrameMotion {
    /// Nothing moves but the eyes.
    pub const STILL: FrameMotion =
        FrameMotion { vectors: false, movers: Vec::new(), uv_scale: [1.0; 2], with_distance: true };
}

impl Default for FrameMotion {
    fn default() -> Self {
        FrameMotion::STILL
    }
}

impl<'a> DeclareContext<'a> {
    /// The extension of type `T` the driver of the graph put in [`DeclareContext::extensions`]
    /// (a renderer's scene for its own passes), if any.
    pub fn extension<T: Any>(&self) -> Option<&'a T> {
        self.extensions.iter().find_map(|e| e.downcast_ref::<T>())
    }
}
