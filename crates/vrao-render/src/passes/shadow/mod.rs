//! Shadow maps with 3×3 PCF (the Czech SSDO thesis §2.1, §5.1) and reflective shadow maps
//! (Lin's NCTU thesis §3.3) for the scene's directional lights: one light-space pass renders,
//! per shadowed light, an orthographic depth map and, when reflective shadow maps are on, each
//! texel's normal and flux. The direct pass looks the depth up (shadow.wgsl);
//! the RSM gather (`passes/rsm`) turns the texels into virtual point lights.
//!
//! The fit: each light's orthographic box encloses every vertex of the scene, in f64
//! light coordinates relative to the scene's anchor, square in the map plane (square
//! texels; the bias formula needs one texel size), with a 4-texel border for the PCF
//! footprint and 0.1 % of slack in depth. Fitting the whole scene rather than what the
//! eyes see is deliberate for VR: the map does not depend on the head, so it neither
//! swims nor shimmers as the head moves (a frustum fit re-rasterises the scene on a
//! new texel grid every frame unless snapped), both eyes look up the very same texels
//! (a frustum fit per eye, or of the union, still moves shadow edges with the head,
//! and different edges in the two eyes are binocular rivalry), and the fit is computed
//! once. The price is resolution on large scenes: a 40 m floor at 2048 texels gets
//! ~2.4 cm texels. Cascades (or a fit to the visible depth range, which needs a GPU
//! reduction) are the way to spend texels on what is near; see the report.

use super::{gpu_scene_of, scene_of, settings_of};
use crate::gpu::kernel::wgsl;
use crate::gpu::raster::{mesh_pipeline, DrawKind, MeshPipeline, MeshPipelines, MESH_ATTRIBUTES};
use crate::gpu::scene::{GpuScene, MESH_WGSL};
use crate::scene::{Light, Scene};
use crate::settings::Settings;
use bytemuck::{Pod, Zeroable};
use glam::{DMat3, DMat4, DVec3, DVec4, Vec3};
use std::sync::Arc;
use vrao_ao::plug::{
    shader_module, uniform_entry, DeclareContext, Gpu, Pass, PassDecl, RecordContext, Resource, Shader, Size, COMMON,
};

/// The pass's name: its declaration in the graph, its timestamp span, and what reports
/// look its cost up by.
pub const NAME: &str = "shadow";

/// Light-space depth of each shadowed directional light (one layer per light, square,
/// `--shadow-size` texels a side), 0 nearest the light, 1 = nothing.
pub const SHADOW_MAP: Resource =
    Resource::attachment("shadow-map", Size::Computed(light_extent), wgpu::TextureFormat::Depth32Float);
/// Reflective shadow map: light-view normal per light-space texel.
pub const RSM_NORMAL: Resource =
    Resource::attachment("rsm-normal", Size::Computed(light_extent), wgpu::TextureFormat::Rgba16Float);
/// Reflective shadow map: flux density (albedo × light irradiance) per texel.
pub const RSM_FLUX: Resource =
    Resource::attachment("rsm-flux", Size::Computed(light_extent), wgpu::TextureFormat::Rgba16Float);

/// shadow.wgsl: the `Shadows` uniform and the PCF lookup the direct and RSM passes share.
pub const SHADOW_WGSL: Shader = wgsl!("src/passes/shadow/shadow.wgsl");

/// Most directional lights with a shadow map (layers of the light-space targets).
pub const MAX_SHADOWED_LIGHTS: usize = 4;

/// Texels of border around the fitted box on each side (the PCF and bilinear reach).
const BORDER_TEXELS: f64 = 4.0;

/// `ShadowLight` of shadow.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct ShadowLightUniform {
    /// Light clip from the scene's anchor frame (orthographic, fitted to the scene).
    pub clip_from_anchored: [[f32; 4]; 4],
    /// Light view from the scene's anchor frame.
    pub view_from_anchored: [[f32; 4]; 4],
    /// Colour × intensity in rgb; w unused.
    pub radiance: [f32; 4],
    /// Texel size p (m), depth range (m), half the map's side (m), unused.
    pub extent: [f32; 4],
    /// The light's index in the scene's light list.
    pub index: [u32; 4],
}

/// `Shadows` of shadow.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct ShadowsUniform {
    /// Number of shadowed lights in `lights` (0: shadows off).
    pub count: u32,
    /// Side of each shadow map layer in texels.
    pub size: u32,
    /// Padding to WGSL's 16-byte alignment.
    pub _pad: [u32; 2],
    /// The shadowed lights; only the first `count` are used.
    pub lights: [ShadowLightUniform; MAX_SHADOWED_LIGHTS],
}

/// The directional lights that get a shadow map: those with a usable direction, in
/// scene order, at most [`MAX_SHADOWED_LIGHTS`].
pub fn shadow_casters(scene: &Scene) -> Vec<usize> {
    scene
        .lights
        .iter()
        .enumerate()
        .filter_map(|(i, light)| match light {
            Light::Directional { direction, .. } if direction.as_dvec3().try_normalize().is_some() => Some(i),
            _ => None,
        })
        .take(MAX_SHADOWED_LIGHTS)
        .collect()
}

/// True when this frame shadows directional light: shadows are on and a light casts.
pub fn shadows_active(scene: &Scene, settings: &Settings) -> bool {
    settings.shadows.enabled && !shadow_casters(scene).is_empty()
}

/// True when this frame adds the reflective-shadow-map bounce.
pub fn rsm_active(scene: &Scene, settings: &Settings) -> bool {
    settings.shadows.rsm && !shadow_casters(scene).is_empty()
}

/// Why the light-space pass does not exist for this scene and these settings, if so.
fn left_out_because(scene: &Scene, settings: &Settings) -> Option<String> {
    let point_lights = scene.lights.iter().filter(|l| matches!(l, Light::Point { .. } | Light::Spot { .. })).count();
    if shadow_casters(scene).is_empty() {
        return Some(if point_lights > 0 {
            format!(
                "no directional light casts shadows (the scene's {point_lights} point or spot light(s) have no shadow maps)"
            )
        } else {
            "the scene has no directional light: nothing casts shadows".to_string()
        });
    }
    if !settings.shadows.enabled && !settings.shadows.rsm {
        return Some("shadows are off and reflective shadow maps are off".to_string());
    }
    None
}

/// The RSM gather radius a scene gets by default: a quarter of its bounding-box
/// diagonal, kept within 0.1 and 4 m.
pub fn suggested_rsm_radius(scene: &Scene) -> f32 {
    let b = scene.bounds();
    let diagonal = if b.is_empty() { 0.0 } else { b.size().length() };
    ((0.25 * diagonal) as f32).clamp(0.1, 4.0)
}

/// Width × height × layers of the light-space targets: the map size (within the
/// device's limit) and one layer per shadowed light.
pub fn light_extent(setup: &DeclareContext, max_dimension: u32) -> (u32, u32, u32) {
    let size = settings_of(setup).shadows.size.min(max_dimension).max(16);
    (size, size, shadow_casters(scene_of(setup)).len().max(1) as u32)
}

/// One light's orthographic fit, in f64.
#[derive(Clone, Debug)]
pub struct LightFit {
    /// The light's index in the scene's light list.
    pub light: usize,
    /// Light view (metres, rigid, looking down −z along the light, origin at the box's
    /// centre on its light-side face) from the anchor frame.
    pub view_from_anchored: DMat4,
    /// Half the side of the fitted square, before the texel border.
    pub half_extent: f64,
    /// Depth range of the box in metres.
    pub range: f64,
    /// The light's colour × intensity.
    pub radiance: Vec3,
}

impl LightFit {
    /// The box around every finite vertex of `scene` (moving meshes wherever their
    /// animation takes them) as seen along `direction`.
    pub fn new(scene: &Scene, anchor: DVec3, light: usize, direction: DVec3, radiance: Vec3) -> LightFit {
        let forward = direction.normalize();
        let helper = if forward.cross(DVec3::Y).length_squared() < 1e-6 { DVec3::Z } else { DVec3::Y };
        let right = forward.cross(helper).normalize();
        let up = right.cross(forward);
        let back = -forward;
        let rotation = DMat3::from_cols(right, up, back).transpose();
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        // Static meshes' vertices, and the corners moving meshes sweep over their animation.
        let swept = scene.swept_corners();
        let static_points = scene
            .meshes
            .iter()
            .filter(|m| m.node.is_none())
            .flat_map(|m| m.positions.iter().map(move |p| (m.origin - anchor) + p.as_dvec3()));
        for anchored in static_points.chain(swept.into_iter().map(|c| c - anchor)) {
            let v = rotation * anchored;
            if v.is_finite() {
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
        // No finite vertex: the bounds are still (+∞, −∞).
        if lo.x > hi.x {
            (lo, hi) = (DVec3::splat(-1.0), DVec3::splat(1.0));
        }
        let centre = (lo + hi) * 0.5;
        let magnitude = lo.abs().max(hi.abs()).max_element();
        let tiny = 1e-6 * magnitude.max(1.0);
        let half_extent = (0.5 * (hi.x - lo.x).max(hi.y - lo.y)).max(tiny);
        let pad = 1e-3 * (hi.z - lo.z) + tiny;
        let top = hi.z + pad;
        let range = (top - (lo.z - pad)).max(tiny);
        let mut view_from_anchored = DMat4::from_mat3(rotation);
        view_from_anchored.w_axis = (-DVec3::new(centre.x, centre.y, top)).extend(1.0);
        LightFit { light, view_from_anchored, half_extent, range, radiance }
    }

    /// Half the map's side with the texel border, at `size` texels a side.
    pub fn half_side(&self, size: u32) -> f64 {
        self.half_extent * size as f64 / (size as f64 - 2.0 * BORDER_TEXELS)
    }

    /// Light clip (x, y in ±1 across the map, z = depth 0..1 from the light) from the
    /// anchor frame.
    pub fn clip_from_anchored(&self, size: u32) -> DMat4 {
        let h = self.half_side(size);
        let clip_from_view = DMat4::from_cols(
            DVec4::new(1.0 / h, 0.0, 0.0, 0.0),
            DVec4::new(0.0, 1.0 / h, 0.0, 0.0),
            DVec4::new(0.0, 0.0, -1.0 / self.range, 0.0),
            DVec4::W,
        );
        clip_from_view * self.view_from_anchored
    }

    /// The light's `ShadowLight` for a map of `size` × `size` texels.
    pub fn uniform(&self, size: u32) -> ShadowLightUniform {
        let half_side = self.half_side(size);
        ShadowLightUniform {
            clip_from_anchored: self.clip_from_anchored(size).as_mat4().to_cols_array_2d(),
            view_from_anchored: self.view_from_anchored.as_mat4().to_cols_array_2d(),
            radiance: self.radiance.extend(0.0).to_array(),
            extent: [(2.0 * half_side / size as f64) as f32, self.range as f32, half_side as f32, 0.0],
            index: [self.light as u32, 0, 0, 0],
        }
    }
}

/// What the light-space pass, the direct pass and the RSM gather share: the fits, the
/// `Shadows` uniforms (all lights, and none), and the comparison sampler.
pub struct LightSpace {
    /// One fit per shadowed light, in [`shadow_casters`] order.
    pub fits: Vec<LightFit>,
    /// `Shadows` with every fitted light; the light-space pass writes it when it runs.
    pub uniform: wgpu::Buffer,
    /// `Shadows` with no light: bound where shadows are off this frame.
    pub none: wgpu::Buffer,
    /// Bilinear depth comparison (lit where reference ≤ stored depth).
    pub comparison: wgpu::Sampler,
}

impl LightSpace {
    /// Fits every shadow-casting light of `scene` (positions relative to `anchor`) and makes the shared buffers.
    pub fn new(gpu: &Gpu, scene: &Scene, anchor: DVec3) -> LightSpace {
        let fits = shadow_casters(scene)
            .into_iter()
            .map(|i| match scene.lights[i] {
                Light::Directional { direction, color, intensity } => {
                    LightFit::new(scene, anchor, i, direction.as_dvec3(), color * intensity)
                }
                Light::Point { .. } | Light::Spot { .. } => unreachable!("shadow casters are directional"),
            })
            .collect();
        let device = &gpu.device;
        let buffer = |label| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: std::mem::size_of::<ShadowsUniform>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let (uniform, none) = (buffer("shadows"), buffer("no shadows"));
        gpu.queue.write_buffer(&none, 0, bytemuck::bytes_of(&ShadowsUniform::zeroed()));
        let comparison = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("shadow comparison"),
            address_mode_u: wgpu::AddressMode::ClampToEdge,
            address_mode_v: wgpu::AddressMode::ClampToEdge,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            compare: Some(wgpu::CompareFunction::LessEqual),
            ..Default::default()
        });
        LightSpace { fits, uniform, none, comparison }
    }

    /// The `Shadows` uniform for maps of `size` texels a side.
    pub fn shadows_uniform(&self, size: u32) -> ShadowsUniform {
        let mut u =
            ShadowsUniform { count: self.fits.len() as u32, size, _pad: [0; 2], lights: [Zeroable::zeroed(); 4] };
        for (slot, fit) in u.lights.iter_mut().zip(&self.fits) {
            *slot = fit.uniform(size);
        }
        u
    }
}

/// The light-space pass: per shadowed light, depth (and with RSM normal and flux).
pub struct ShadowPass {
    light_space: Arc<LightSpace>,
    /// One per kind of draw the scene has, depth only and with the RSM's targets.
    depth_only: MeshPipelines,
    reflective: MeshPipelines,
    /// One uniform (`ShadowLight`) and bind group per fitted light.
    light_buffers: Vec<wgpu::Buffer>,
    light_groups: Vec<wgpu::BindGroup>,
}

impl ShadowPass {
    /// Makes the light-space pipelines (depth-only, and reflective for the RSM) and one bind group per fitted light.
    pub fn new(gpu: &Gpu, scene: &GpuScene, light_space: Arc<LightSpace>) -> ShadowPass {
        let device = &gpu.device;
        let light_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("shadow light"),
            entries: &[uniform_entry(0, wgpu::ShaderStages::VERTEX_FRAGMENT)],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("shadow"),
            bind_group_layouts: &[Some(&light_layout), Some(&scene.material_layout)],
            immediate_size: 0,
        });
        let module = shader_module(
            gpu,
            "shadow map",
            &[COMMON, SHADOW_WGSL, MESH_WGSL, wgsl!("src/passes/shadow/shadow_map.wgsl")],
        );
        let variants = |reflective: bool| {
            MeshPipelines::new(&scene.kinds, |kind| pipeline(device, &layout, &module, reflective, kind))
        };
        let depth_only = variants(false);
        let reflective = variants(true);
        let light_buffers: Vec<wgpu::Buffer> = light_space
            .fits
            .iter()
            .map(|_| {
                device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("shadow light"),
                    size: std::mem::size_of::<ShadowLightUniform>() as u64,
                    usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                })
            })
            .collect();
        let light_groups = light_buffers
            .iter()
            .map(|b| {
                device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("shadow light"),
                    layout: &light_layout,
                    entries: &[wgpu::BindGroupEntry { binding: 0, resource: b.as_entire_binding() }],
                })
            })
            .collect();
        ShadowPass { light_space, depth_only, reflective, light_buffers, light_groups }
    }
}

fn pipeline(
    device: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    reflective: bool,
    kind: DrawKind,
) -> wgpu::RenderPipeline {
    let alpha_test = kind.alpha_test;
    let targets = [RSM_NORMAL, RSM_FLUX].map(|r| Some(wgpu::ColorTargetState::from(r.format())));
    // The depth-only map has no fragment stage unless it must discard holes.
    let fragment = match (reflective, alpha_test) {
        (true, _) => Some(("fs_rsm", &targets[..])),
        (false, true) => Some(("fs_alpha", &[][..])),
        (false, false) => None,
    };
    mesh_pipeline(
        device,
        MeshPipeline {
            label: if reflective { "reflective shadow map" } else { "shadow map" },
            layout,
            module,
            vertex: ("vs_main", &MESH_ATTRIBUTES),
            // 0 nearest the light.
            depth: (SHADOW_MAP.format(), wgpu::CompareFunction::Less),
            fragment,
            multiview_mask: None,
            alpha_test,
            cull: kind.cull.then_some(wgpu::Face::Back),
        },
    )
}

impl Pass for ShadowPass {
    fn declare(&self, setup: &DeclareContext) -> PassDecl {
        let (scene, settings) = (scene_of(setup), settings_of(setup));
        let mut decl = PassDecl::new(NAME).write(SHADOW_MAP);
        if rsm_active(scene, settings) {
            decl = decl.write(RSM_NORMAL).write(RSM_FLUX);
        }
        let lights = self.light_space.fits.len();
        let size = settings.shadows.size;
        let texel_cm =
            self.light_space.fits.iter().map(|f| 200.0 * f.half_side(size) / size as f64).fold(0.0, f64::max);
        let skipped = scene.lights.iter().filter(|l| matches!(l, Light::Directional { .. })).count() - lights;
        let mut note = format!(
            "{lights} directional light(s), {size}×{size} texels of {texel_cm:.2} cm fitted to the scene{}",
            if rsm_active(scene, settings) { ", with reflective shadow maps (normal, flux)" } else { "" }
        );
        if skipped > 0 {
            note += &format!("; {skipped} more directional light(s) unshadowed");
        }
        match left_out_because(scene, settings) {
            Some(reason) => decl.disabled_if(true, reason),
            None => decl.note(note),
        }
    }

    fn record(&self, ctx: &mut RecordContext) {
        let gpu_scene = gpu_scene_of(ctx.setup);
        let size = ctx.target(SHADOW_MAP).width;
        let uniform = self.light_space.shadows_uniform(size);
        ctx.gpu.queue.write_buffer(&self.light_space.uniform, 0, bytemuck::bytes_of(&uniform));
        let reflective = rsm_active(scene_of(ctx.setup), settings_of(ctx.setup));
        let targets = ctx.targets;
        for (layer, (buffer, group)) in self.light_buffers.iter().zip(&self.light_groups).enumerate() {
            ctx.gpu.queue.write_buffer(buffer, 0, bytemuck::bytes_of(&uniform.lights[layer]));
            let color = |r: Resource| {
                Some(wgpu::RenderPassColorAttachment {
                    view: &targets[&r].layer_views[layer],
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                })
            };
            let colors = if reflective { vec![color(RSM_NORMAL), color(RSM_FLUX)] } else { vec![] };
            let mut pass = ctx.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("shadow"),
                color_attachments: &colors,
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &targets[&SHADOW_MAP].layer_views[layer],
                    depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Store }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_bind_group(0, group, &[]);
            gpu_scene.draw_with(&mut pass, if reflective { &self.reflective } else { &self.depth_only });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use vrao_ao::layout_check::{self, mirror};

    #[test]
    fn the_shadow_uniforms_match_shadow_wgsl() {
        // The files of the light-space pass (`ShadowPass::new`).
        let files = [COMMON, SHADOW_WGSL, MESH_WGSL, wgsl!("src/passes/shadow/shadow_map.wgsl")];
        #[rustfmt::skip]
        layout_check::check(&[
            mirror!(ShadowLightUniform, files, "ShadowLight", [clip_from_anchored, view_from_anchored, radiance, extent, index]),
            mirror!(ShadowsUniform, files, "Shadows", [count, size, _pad, lights]),
        ]);
    }

    fn sun(direction: Vec3) -> Scene {
        let mut scene = Scene::load("builtin:box").unwrap();
        scene.lights = vec![Light::Directional { direction, color: Vec3::ONE, intensity: 2.0 }];
        scene
    }

    #[test]
    fn every_vertex_lands_inside_the_map_and_its_depth_range() {
        for direction in [Vec3::new(1.0, -2.0, -1.0), Vec3::NEG_Y, Vec3::Y, Vec3::new(0.0, -1e-3, 1.0)] {
            let scene = sun(direction);
            let anchor = scene.bounds().center();
            let fit = LightFit::new(&scene, anchor, 0, direction.as_dvec3(), Vec3::ONE);
            let clip = fit.clip_from_anchored(2048);
            for mesh in &scene.meshes {
                for p in &mesh.positions {
                    let c = clip * (mesh.origin - anchor + p.as_dvec3()).extend(1.0);
                    let border = 1.0 - 2.0 * BORDER_TEXELS / 2048.0;
                    assert!(c.x.abs() <= border + 1e-9 && c.y.abs() <= border + 1e-9, "{direction}: {c}");
                    assert!(c.z > 0.0 && c.z < 1.0, "{direction}: depth {}", c.z);
                }
            }
        }
    }

    #[test]
    fn depth_grows_along_the_light_and_the_view_is_rigid() {
        let d = Vec3::new(1.0, -2.0, -1.0);
        let scene = sun(d);
        let fit = LightFit::new(&scene, DVec3::ZERO, 0, d.as_dvec3(), Vec3::ONE);
        let clip = fit.clip_from_anchored(512);
        let a = clip * DVec4::new(0.0, 0.5, 0.0, 1.0);
        let b = clip * (DVec3::new(0.0, 0.5, 0.0) + d.as_dvec3().normalize()).extend(1.0);
        assert!(b.z > a.z, "farther along the light is deeper");
        assert!(((b.z - a.z) * fit.range - 1.0).abs() < 1e-9, "depth is linear in metres");
        let m = DMat3::from_mat4(fit.view_from_anchored);
        assert!((m * m.transpose()).abs_diff_eq(DMat3::IDENTITY, 1e-12));
        // The light view's +z points at the light.
        assert!((m * -d.as_dvec3().normalize() - DVec3::Z).length() < 1e-12);
    }

    #[test]
    fn only_directional_lights_cast_and_at_most_four() {
        let mut scene = sun(Vec3::NEG_Y);
        assert_eq!(shadow_casters(&scene), vec![0]);
        scene.lights = vec![Light::Point { position: DVec3::Y, color: Vec3::ONE, intensity: 1.0 }];
        assert!(shadow_casters(&scene).is_empty());
        scene.lights = vec![Light::Directional { direction: Vec3::ZERO, color: Vec3::ONE, intensity: 1.0 }; 2];
        assert!(shadow_casters(&scene).is_empty(), "a zero direction casts nothing");
        scene.lights = vec![Light::Directional { direction: Vec3::X, color: Vec3::ONE, intensity: 1.0 }; 6];
        assert_eq!(shadow_casters(&scene).len(), MAX_SHADOWED_LIGHTS);
    }
}
