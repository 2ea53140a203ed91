//! The AO engine: vrao's ambient occlusion over depth (and optionally normals) that
//! someone else rendered. A wgpu program makes an [`AoEngine`] from its own device and
//! queue, and each frame hands it its depth buffer and each view's matrices; the engine
//! records its passes into the program's command encoder and returns the AO, a layered
//! texture the program samples. vrao's renderer (vrao-render) runs the same chain
//! ([`crate::passes::ao_chain`]) over its G-buffer through the same frame driver
//! ([`crate::driver::GraphDriver`]): one implementation.
//!
//! What the engine runs, in order: [`import`] (the host's depth in any convention into
//! reversed-Z infinite-far `Depth32Float`, likewise its second depth layer when two are
//! read, and its normals, or normals rebuilt from the depth, into view space), the chosen
//! technique, temporal accumulation, the denoise and the upsampling from half resolution,
//! each left out when the settings do not need it.
//! SSDO (`ssdo`, `ssdo-bounce`) gathers the host's light beside the AO when the frame
//! gives it ([`AoFrame::light`]: the direct light per view, the environment's SH): the
//! output's rgb is then the ambient irradiance (environment through the unoccluded
//! directions plus one bounce) to multiply by albedo/π; without it SSDO is an AO
//! technique.
//!
//! Conventions (what [`AoFrame`] must hold): right-handed view space (x right, y up,
//! looking down −z, as glam's `camera::rh::view::look_at_mat4`); perspective projections with clip w = −z
//! and depth in 0..1 (wgpu's), standard or reversed, finite or infinite far, as the
//! frame's [`DepthConvention`] says; one depth layer per view, and a second one behind it
//! where the host peels one ([`AoFrame::second_layer`]).

pub(crate) mod exclusion;
mod host_texture;
pub(crate) mod import;
pub(crate) mod light;
mod pack;

pub use exclusion::HostExclusion;
pub use light::HostLight;
pub use pack::AoOutputFormat;

use crate::driver::{FrameParams, GraphDriver, Submission};
use crate::error::{Error, Result};
use crate::gpu::timing::{PassTimer, SpanRecorder};
use crate::gpu::uniforms::FrameLighting;
use crate::gpu::Gpu;
use crate::graph::{Plan, FINAL_AO};
use crate::passes::{self, ChainSettings, FrameMotion, Pass, RightEyeTiles};
use crate::settings::{AoSettings, Technique};
use crate::stereo::{Eye, EyeSide, Fov, HeadPose};
use glam::{DMat4, DQuat, Mat4};
use import::{ImportPass, ImportSource, HOST_DEPTH, HOST_DEPTH_LAYER_2, HOST_MOTION, HOST_NORMALS};
use pack::PackPass;
use std::sync::Arc;

/// How the host's depth buffer maps distance to depth.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DepthConvention {
    /// Near plane at depth 1 and far at 0 (reversed-Z); false: near at 0, far at 1.
    pub reversed_z: bool,
    /// The far plane is at infinity (the projection has no far distance).
    pub infinite_far: bool,
}

impl DepthConvention {
    /// Reversed-Z with the far plane at infinity: vrao's own, and the best precision.
    pub const REVERSED_INFINITE: DepthConvention = DepthConvention { reversed_z: true, infinite_far: true };
    /// Depth 0 at the near plane and 1 at a finite far plane (glam's `camera::rh::proj::directx::perspective`).
    pub const STANDARD_FINITE: DepthConvention = DepthConvention { reversed_z: false, infinite_far: false };
}

/// The space the host's normals are in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NormalSpace {
    /// View space of each view (what vrao's G-buffer holds).
    View,
    /// World space: the engine turns them by each view's rotation.
    World,
}

/// How the host's normal texture stores a unit vector.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NormalEncoding {
    /// xyz in −1..1 (float or snorm formats).
    Signed,
    /// xyz × 0.5 + 0.5 (unorm formats such as `Rgb10a2Unorm` or `Rgba8Unorm`).
    Unsigned,
}

/// The host's normals: a float-sampled texture with one layer per view.
#[derive(Clone, Copy, Debug)]
pub struct HostNormals<'a> {
    /// The texture (`TEXTURE_BINDING`; xyz read, w ignored).
    pub texture: &'a wgpu::Texture,
    /// The space the normals are in.
    pub space: NormalSpace,
    /// How they are encoded.
    pub encoding: NormalEncoding,
}

/// The host's motion vectors: where each pixel's surface point was in the previous frame,
/// as a float-sampled texture (`Rg16Float`, `Rgba16Float`, `Rg32Float`, …) with one
/// layer per view, xy read. Temporal accumulation then carries moving objects' history
/// with them instead of rejecting it (`AoSettings::temporal`).
#[derive(Clone, Copy, Debug)]
pub struct HostMotion<'a> {
    /// The texture (`TEXTURE_BINDING`), the engine's size.
    pub texture: &'a wgpu::Texture,
    /// Multiplies a texel's xy into the uv offset to the previous frame (uv 0..1 from the
    /// top-left): `[1/width, 1/height]` for pixels pointing from this frame to the
    /// previous, `[0.5, -0.5]` for NDC offsets, negated when the vectors point from the
    /// previous frame to this one.
    pub to_previous_uv: [f32; 2],
}

/// One view's matrices, as the host rendered its depth with them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewMatrices {
    /// View from world: a rigid transform (rotation and translation).
    pub view: Mat4,
    /// Clip from view: a perspective projection (clip w = −z).
    pub projection: Mat4,
}

/// What the host gives the engine each frame.
#[derive(Clone, Copy, Debug)]
pub struct AoFrame<'a> {
    /// The depth buffer: `Depth32Float`, `Depth24Plus`, `Depth16Unorm` (or a depth-stencil
    /// format), one layer per view (a 2-layer array for stereo, a plain 2D texture for
    /// mono), the engine's size, one sample, `TEXTURE_BINDING`.
    pub depth: &'a wgpu::Texture,
    /// How `depth` maps distance to depth.
    pub depth_convention: DepthConvention,
    /// The host's second depth layer (its own depth peel: the nearest surface behind
    /// `depth`'s, best its nearest back face where the winding is trusted, so that a
    /// sheet has nothing behind it: the engine takes every surface of it as a back face,
    /// the span to it solid), or `None` for one layer. Read only when `AoSettings::layers` is 2, by
    /// the techniques that read two layers (GTAO, SSDO): their samples then block the span
    /// back to it instead of a slab `gtao.thickness` deep. The same rules as `depth`: a
    /// depth format of that list, its convention, one layer per view, the engine's size,
    /// `TEXTURE_BINDING`, and `depth`'s sample count (where that is more than one, each
    /// pixel reads the second layer at the sample the depth's resolve took). Where nothing
    /// lies behind, it must hold the convention's far value (1 standard, 0 reversed-Z),
    /// as a peel cleared to the far plane leaves it; the thickness then stays, as it
    /// does wherever the second layer does not lie behind the first. The engine does not
    /// peel: a minimum separation behind the first (`AoSettings::layer_separation`, the
    /// renderer's) is the host's peel's to keep. Checked whenever given.
    pub second_layer: Option<&'a wgpu::Texture>,
    /// The host's normals, or `None` to rebuild them from the depth.
    pub normals: Option<HostNormals<'a>>,
    /// Each view's matrices, one per view (left eye first).
    pub views: &'a [ViewMatrices],
    /// The host's motion vectors, or `None`: temporal accumulation then reprojects by the
    /// views' motion alone (right for a still scene).
    pub motion: Option<HostMotion<'a>>,
    /// The host's light for SSDO (its direct light and environment), or `None`: SSDO then
    /// returns AO alone; the other techniques never read it.
    pub light: Option<HostLight<'a>>,
    /// What the host leaves out (hands, controllers, UI panels), or `None`: every pixel
    /// casts and receives AO.
    pub exclusion: Option<HostExclusion<'a>>,
}

/// What the engine is made for: the AO settings, the size of each view and their number.
#[derive(Clone, Debug, PartialEq)]
pub struct AoConfig {
    /// Technique, quality, radius, resolution, denoise, temporal accumulation.
    pub settings: AoSettings,
    /// Width of each view in pixels.
    pub width: u32,
    /// Height of each view in pixels.
    pub height: u32,
    /// 1 (mono) or 2 (stereo).
    pub views: u32,
}

impl AoConfig {
    /// The largest view side the engine takes, in pixels.
    pub const MAX_SIDE: u32 = MAX_SIDE;
    /// The samples per pixel a host's depth, normals and motion may have (a multisampled
    /// texture is resolved in the engine's import pass).
    pub const SAMPLE_COUNTS: [u32; 4] = import::SAMPLE_COUNTS;
}

/// The engine's AO for the frame just recorded: full resolution, one layer per view, the
/// ambient visibility (1 open, 0 fully occluded) in alpha of `Rgba16Float` or in red of a
/// single-channel format ([`AoEngine::set_output_format`]).
pub struct AoOutput<'a> {
    /// The texture (it can be sampled and copied from).
    pub texture: &'a wgpu::Texture,
    /// A `D2Array` view of all its layers.
    pub view: &'a wgpu::TextureView,
}

impl AoOutput<'_> {
    /// The texel format: `R16Float` holds the visibility in red, `R8Unorm` likewise, and
    /// `Rgba16Float` in alpha (with SSDO's light in rgb).
    pub fn format(&self) -> wgpu::TextureFormat {
        self.texture.format()
    }
}

/// vrao's AO chain over a host's depth: made once for the life of the host's window
/// ([`AoEngine::resize`] follows it), recorded into the host's encoder each frame.
pub struct AoEngine {
    gpu: Arc<Gpu>,
    config: AoConfig,
    import: ImportPass,
    chain: Vec<Box<dyn Pass>>,
    /// Plans by settings, whether the host gave motion and whether it gave direct light.
    driver: GraphDriver<(ChainSettings, bool, bool)>,
    /// Packs the host's direct light for SSDO's bounce.
    light_import: light::LightImportPass,
    /// The copy into a single-channel output, and the format chosen.
    pack: PackPass,
    output_format: Option<AoOutputFormat>,
    /// Whether this frame has the host's motion vectors.
    motion: FrameMotion,
    /// The host's visibility mask, one per view ([`AoEngine::set_visibility_mask`]).
    mask: Option<crate::visibility::VisibilityMask>,
}

impl AoEngine {
    /// The engine on a host's device: the device is checked for what the kernels need
    /// (a refusal names the missing capability) and the settings are validated. The
    /// host's uncaptured-error handler is left alone.
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue, config: &AoConfig) -> Result<AoEngine> {
        let mut gpu = Gpu::from_host(device, queue)?;
        // Each kernel compiles at its first frame: the host pays for the technique, denoise
        // and upsampling it runs, and another technique costs its build when first chosen.
        gpu.set_lazy_pipelines(true);
        let gpu = Arc::new(gpu);
        host_settings(config, crate::stereo::DEFAULT_NEAR)?;
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let chain = passes::ao_chain(&gpu, Vec::new());
        let import = ImportPass::new(&gpu);
        let light_import = light::LightImportPass::new(&gpu);
        let pack = PackPass::new(&gpu);
        let driver = GraphDriver::new(&gpu, PassTimer::disabled(&gpu)?);
        if let Some(error) = pollster::block_on(scope.pop()) {
            return Err(Error::Device(format!("the AO engine's pipelines: {error}")));
        }
        gpu.take_shader_error()?;
        Ok(AoEngine {
            gpu,
            config: config.clone(),
            import,
            light_import,
            chain,
            driver,
            pack,
            output_format: None,
            motion: FrameMotion::STILL,
            mask: None,
        })
    }

    /// The headset's visibility mask, one [`crate::visibility::ViewMask`] per view (from
    /// `xrGetVisibilityMaskKHR`, say), or `None`. With [`AoSettings::mask`] on, every pass
    /// leaves the hidden pixels out: their AO reads 1 and costs no fetches.
    pub fn set_visibility_mask(&mut self, mask: Option<crate::visibility::VisibilityMask>) {
        self.mask = mask;
    }

    /// The share of each view's pixels the mask hid in the last frame (empty before one).
    pub fn hidden_share(&self) -> &[f64] {
        self.driver.visibility().hidden_share()
    }

    /// Changes the AO settings (validated; a different technique or resolution
    /// restarts temporal accumulation).
    pub fn set_settings(&mut self, settings: &AoSettings) -> Result<()> {
        let config = AoConfig { settings: settings.clone(), ..self.config.clone() };
        host_settings(&config, crate::stereo::DEFAULT_NEAR)?;
        if config.settings != self.config.settings {
            self.driver.reset_history();
        }
        self.config = config;
        Ok(())
    }

    /// Follows the host's window to a new size per view: the next frame's targets are
    /// made at that size; no pipeline is rebuilt. Temporal accumulation starts afresh.
    pub fn resize(&mut self, width: u32, height: u32) -> Result<()> {
        let config = AoConfig { width, height, ..self.config.clone() };
        host_settings(&config, crate::stereo::DEFAULT_NEAR)?;
        if (width, height) != (self.config.width, self.config.height) {
            self.driver.reset_history();
        }
        self.config = config;
        Ok(())
    }

    /// The texel format of the AO the next frames return: the visibility alone in
    /// `R16Float` or `R8Unorm`, or `Rgba16Float` (visibility in alpha, SSDO's light in
    /// rgb); `None` (the default) returns the chain's own final texture, which is
    /// `R16Float` for GTAO, SSAO and HBAO on a device that writes `R16Float` storage and
    /// `Rgba16Float` otherwise ([`AoOutput::format`]). Where the chain's final texture has
    /// the asked format already it is returned as it is; otherwise one full-screen draw
    /// per view copies it.
    pub fn set_output_format(&mut self, format: Option<AoOutputFormat>) {
        self.output_format = format;
    }

    /// Compute pipelines the engine has compiled so far: the chosen technique's chain
    /// after the first frame; a resize adds none.
    pub fn pipelines_built(&self) -> usize {
        self.gpu.pipelines_built()
    }

    /// The configuration the next frame runs with.
    pub fn config(&self) -> &AoConfig {
        &self.config
    }

    /// Forgets the previous frame (a camera cut): temporal accumulation starts afresh.
    pub fn reset_history(&mut self) {
        self.driver.reset_history();
    }

    /// The passes the last frame ran and the ones it left out, with the reasons.
    pub fn last_plan(&self) -> Option<&Plan> {
        self.driver.last_plan()
    }

    /// Per pass, the right eye's tiles the chain computed rather than copied from the
    /// left eye in the last frame, read back once the GPU finished it (blocking: for
    /// reports); empty when the right eye reuses nothing.
    pub fn right_eye_tiles(&self) -> Vec<RightEyeTiles> {
        let passes: Vec<&dyn Pass> = self.chain.iter().map(|p| p.as_ref()).collect();
        RightEyeTiles::latest(&passes, &self.gpu)
    }

    /// Records one frame of AO into `encoder` from the host's depth (and normals) and
    /// returns the AO texture; the host submits the encoder. Bad input (a texture of the
    /// wrong size, format or usage, matrices that are not a rigid view and a perspective
    /// projection of the stated depth convention) is an `Error::Input` naming it, before
    /// anything is recorded.
    pub fn record(&mut self, encoder: &mut wgpu::CommandEncoder, frame: &AoFrame) -> Result<AoOutput<'_>> {
        self.record_inner(encoder, frame, None)
    }

    /// [`AoEngine::record`], with a timestamp span per pass (under the pass's name:
    /// `import`, `gtao`, `denoise`, …) recorded into the host's `profiler`, so the host
    /// reads the AO chain's GPU milliseconds with its own frames.
    pub fn record_profiled(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        frame: &AoFrame,
        profiler: &wgpu_profiler::GpuProfiler,
    ) -> Result<AoOutput<'_>> {
        self.record_inner(encoder, frame, Some(profiler))
    }

    fn record_inner(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        frame: &AoFrame,
        spans: Option<&dyn SpanRecorder>,
    ) -> Result<AoOutput<'_>> {
        let config = &self.config;
        let (eyes, projections) = views_of(frame, config.views)?;
        let source = ImportSource::check(frame, config, &projections)?;
        let settings = host_settings(config, projections[0].near)?;
        let layers = config.views;
        // The host's second layer counts only where two layers are asked for.
        let second_layer = frame.second_layer.filter(|_| config.settings.layers == 2);
        self.import_host_buffers(frame, second_layer, layers);
        let mask = frame.exclusion.as_ref().map(|e| exclusion::mask_view(e, &self.config)).transpose()?;
        let receive_none = frame.exclusion.map_or(0, |e| e.receive_none);
        self.import.set_source(source, mask.clone());
        // SSDO's light: the host's direct light (imported, then packed with the depth by
        // the light import pass) and its environment's quadratics in each view.
        let direct = self.import_direct_light(frame, layers)?;
        let environment = environment_quadratics(frame, &eyes)?;
        let lighting = FrameLighting { environment: environment.as_ref(), ..FrameLighting::NONE };
        let light_inputs = crate::passes::ssdo::LightInputs { direct: direct.is_some() };
        let params = FrameParams {
            settings: &settings,
            extensions: &[&light_inputs],
            alpha_cards: false,
            second_layer: second_layer.is_some(),
            anchor: glam::DVec3::ZERO,
            multiview: false,
            motion: &self.motion,
            mask: self.mask.as_ref(),
            scalar_chain: self.gpu.caps.scalar_chain,
        };
        let passes: Vec<&dyn Pass> = [&self.import as &dyn Pass, &self.light_import as &dyn Pass]
            .into_iter()
            .chain(self.chain.iter().map(|p| p.as_ref()))
            .collect();
        let imported = imported_resources(frame, second_layer.is_some(), direct.is_some());
        let key = (settings.clone(), frame.motion.is_some(), direct.is_some());
        let plan = self.driver.plan(&key, &passes, &params, layers, &[FINAL_AO], &imported)?;
        self.driver.prepare(&self.gpu, &plan, &params, &lighting, &eyes);
        // Kernels compile at their first frame: a device that cannot build one is refused
        // here, as a typed error, not through the host's uncaptured-error handler.
        let recorded = pipeline_errors_as_device(&self.gpu, || {
            self.driver.record(&self.gpu, encoder, &passes, &plan, &params, &eyes, None, spans, Submission::OneEncoder)
        })?;
        recorded?;
        self.driver.end_frame(&eyes);
        let receiving = mask.filter(|_| receive_none != 0).map(|view| (view, receive_none));
        self.output(encoder, &plan, spans, receiving)
    }

    /// Imports the host's depth, and its second depth layer (when read), normals and
    /// motion vectors when given, as this frame's graph inputs, and notes whether the
    /// frame has motion vectors.
    fn import_host_buffers(&mut self, frame: &AoFrame, second_layer: Option<&wgpu::Texture>, layers: u32) {
        let targets = self.driver.targets_mut();
        targets.import(&self.gpu, HOST_DEPTH, frame.depth, wgpu::TextureAspect::DepthOnly, layers);
        if let Some(second) = second_layer {
            targets.import(&self.gpu, HOST_DEPTH_LAYER_2, second, wgpu::TextureAspect::DepthOnly, layers);
        }
        if let Some(normals) = &frame.normals {
            targets.import(&self.gpu, HOST_NORMALS, normals.texture, wgpu::TextureAspect::All, layers);
        }
        self.motion = match &frame.motion {
            Some(motion) => {
                targets.import(&self.gpu, HOST_MOTION, motion.texture, wgpu::TextureAspect::All, layers);
                FrameMotion {
                    vectors: true,
                    uv_scale: motion.to_previous_uv,
                    with_distance: false,
                    ..FrameMotion::STILL
                }
            }
            None => FrameMotion::STILL,
        };
    }

    /// Checks and imports the host's direct light for SSDO, when the frame gives it: the
    /// light import pass samples it as float, so an integer format is refused.
    fn import_direct_light<'f>(&mut self, frame: &AoFrame<'f>, layers: u32) -> Result<Option<&'f wgpu::Texture>> {
        let direct = frame.light.and_then(|l| l.direct);
        if let Some(texture) = direct {
            host_texture::check_texture("direct light", texture, &self.config)?;
            if texture.format().sample_type(None, None) != Some(wgpu::TextureSampleType::Float { filterable: true })
                && texture.format().sample_type(None, None)
                    != Some(wgpu::TextureSampleType::Float { filterable: false })
            {
                return Err(Error::input(format!("direct light: format {:?} is not float-sampled", texture.format())));
            }
            self.driver.targets_mut().import(&self.gpu, light::HOST_DIRECT, texture, wgpu::TextureAspect::All, layers);
        }
        Ok(direct)
    }

    /// The final AO target the plan resolved, as the host asked for it: the chain's own
    /// `Rgba16Float` texture, or its copy packed into a single-channel format (or copied
    /// with AO 1 where the host's mask says a pixel receives none).
    fn output(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        plan: &Plan,
        spans: Option<&dyn SpanRecorder>,
        receiving: Option<(wgpu::TextureView, u32)>,
    ) -> Result<AoOutput<'_>> {
        let output = plan.resolve(FINAL_AO).ok_or_else(|| Error::Plan("nothing provides the final AO".into()))?;
        let target = self
            .driver
            .targets()
            .targets
            .get(&output)
            .ok_or_else(|| Error::Plan(format!("{} was not allocated", output.name())))?;
        let chain_own = if target.format == AoOutputFormat::R16Float.texture_format() {
            AoOutputFormat::R16Float
        } else {
            AoOutputFormat::Rgba16Float
        };
        let format = self.output_format.unwrap_or(chain_own);
        if format == chain_own && receiving.is_none() {
            return Ok(AoOutput { texture: &target.texture, view: &target.array_view });
        }
        let span = spans.map(|s| (s, s.begin(encoder, "pack")));
        let packed = self.pack.record(&self.gpu, encoder, target, format, receiving);
        if let Some((s, span)) = span {
            s.end(encoder, span);
        }
        Ok(AoOutput { texture: &packed.texture, view: &packed.array_view })
    }
}

/// The host environment's SH turned into each view's quadratics (SSDO's ambient light),
/// or `None` without one; a coefficient that is not finite is refused.
fn environment_quadratics(frame: &AoFrame, eyes: &[Eye]) -> Result<Option<[[[f32; 4]; 10]; 4]>> {
    let environment = frame.light.and_then(|l| l.environment_sh).map(|sh| {
        let coefficients = sh.map(glam::Vec3::from_array);
        let rotations: Vec<glam::Mat3> =
            eyes.iter().map(|eye| glam::Mat3::from_quat(eye.pose.orientation.as_quat())).collect();
        crate::sh::view_quadratics(&coefficients, &rotations)
    });
    if environment.is_some_and(|q| !q.iter().flatten().flatten().all(|v| v.is_finite())) {
        return Err(Error::input("environment SH: a coefficient is not finite"));
    }
    Ok(environment)
}

/// The graph inputs this frame imports from the host: its depth always, and its second
/// depth layer (when read), normals, motion vectors and direct light when given.
fn imported_resources(frame: &AoFrame, second_layer: bool, direct: bool) -> Vec<crate::graph::Resource> {
    let mut imported = vec![HOST_DEPTH];
    imported.extend(second_layer.then_some(HOST_DEPTH_LAYER_2));
    imported.extend(frame.normals.is_some().then_some(HOST_NORMALS));
    imported.extend(frame.motion.is_some().then_some(HOST_MOTION));
    imported.extend(direct.then_some(light::HOST_DIRECT));
    imported
}

/// Runs `record` inside a validation error scope, so a kernel the device cannot build
/// comes back as a typed `Error::Device` rather than through the host's handler.
fn pipeline_errors_as_device<T>(gpu: &Gpu, record: impl FnOnce() -> T) -> Result<T> {
    let scope = gpu.device.push_error_scope(wgpu::ErrorFilter::Validation);
    let recorded = record();
    if let Some(error) = pollster::block_on(scope.pop()) {
        return Err(Error::Device(format!("the AO engine's pipelines: {error}")));
    }
    Ok(recorded)
}

/// The largest view side the engine takes, in pixels.
pub(crate) const MAX_SIDE: u32 = 8192;

/// The renderer settings the engine's passes read: the host's AO settings, its size as
/// the profile's, and its near plane. A technique whose pass only vrao's renderer has
/// (the `measurement` feature's point-sampled SSDO) is refused.
fn host_settings(config: &AoConfig, near: f64) -> Result<ChainSettings> {
    if config.views == 0 || config.views > 2 {
        return Err(Error::input(format!("the AO engine renders 1 or 2 views, not {}", config.views)));
    }
    if config.settings.technique.renderer_only() {
        return Err(Error::input(format!(
            "technique {} samples vrao's renderer's own buffers: the AO engine offers {}",
            config.settings.technique.name(),
            Technique::ALL.iter().filter(|t| !t.renderer_only()).map(|t| t.name()).collect::<Vec<_>>().join(", ")
        )));
    }
    if !(1..=MAX_SIDE).contains(&config.width) || !(1..=MAX_SIDE).contains(&config.height) {
        return Err(Error::input(format!(
            "the AO engine's size {}x{} is not within 1..={MAX_SIDE} per side",
            config.width, config.height
        )));
    }
    config.settings.validate()?;
    Ok(ChainSettings { width: config.width, height: config.height, near, ao: config.settings.clone() })
}

/// Each view as an [`Eye`] (pose from the view matrix, field of view from the
/// projection), and each view's projection as read (the engine's near plane is the
/// first one's).
fn views_of(frame: &AoFrame, views: u32) -> Result<(Vec<Eye>, Vec<Projection>)> {
    if frame.views.len() != views as usize {
        return Err(Error::input(format!(
            "the frame gives {} views' matrices; the engine renders {views}",
            frame.views.len()
        )));
    }
    let mut eyes = Vec::with_capacity(frame.views.len());
    let mut projections = Vec::with_capacity(frame.views.len());
    for (index, m) in frame.views.iter().enumerate() {
        let side = if index == 0 { EyeSide::Left } else { EyeSide::Right };
        let projection = Projection::of(&m.projection, frame.depth_convention, &format!("view {index}: projection"))?;
        let pose = rigid_pose(&m.view, &format!("view {index}: view matrix"))?;
        eyes.push(Eye { side, pose, fov: projection.fov });
        projections.push(projection);
    }
    Ok((eyes, projections))
}

/// The head pose whose view-from-world is `view`: refused unless it is a finite rigid
/// transform (orthonormal rotation within 1e-3, no projection row); errors start with `what`.
fn rigid_pose(view: &Mat4, what: &str) -> Result<HeadPose> {
    let view = view.as_dmat4();
    if !view.is_finite() {
        return Err(Error::input(format!("{what}: not finite")));
    }
    let world_from_view = view.inverse();
    let rotation = glam::DMat3::from_mat4(world_from_view);
    let orthonormal =
        (rotation.transpose() * rotation - glam::DMat3::IDENTITY).to_cols_array().iter().all(|e| e.abs() < 1e-3);
    let last_row = view.row(3);
    if !orthonormal || rotation.determinant() < 0.0 || (last_row - glam::DVec4::W).abs().max_element() > 1e-6 {
        return Err(Error::input(format!(
            "{what}: not a rigid transform (rotation and translation only, right-handed)"
        )));
    }
    let orientation = DQuat::from_mat3(&rotation).normalize();
    Ok(HeadPose { position: world_from_view.w_axis.truncate(), orientation })
}

/// What the engine reads from a host's perspective projection.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Projection {
    /// The frustum's angles.
    pub fov: Fov,
    /// Distance of the near plane (where depth is 1 reversed, 0 standard).
    pub near: f64,
    /// distance = `depth_numerator` / (depth + `depth_offset`).
    pub depth_offset: f64,
    /// See `depth_offset`.
    pub depth_numerator: f64,
}

impl Projection {
    /// Reads `projection` as a right-handed perspective of the stated convention; errors
    /// start with `what`.
    pub(crate) fn of(projection: &Mat4, convention: DepthConvention, what: &str) -> Result<Projection> {
        let refuse = |why: String| Err(Error::input(format!("{what}: {why}")));
        let p: DMat4 = projection.as_dmat4();
        if !p.is_finite() {
            return refuse("not finite".into());
        }
        let (p00, p11, p20, p21) = (p.x_axis.x, p.y_axis.y, p.z_axis.x, p.z_axis.y);
        let (p22, p23, p32, p33) = (p.z_axis.z, p.z_axis.w, p.w_axis.z, p.w_axis.w);
        let skew = [p.x_axis.y, p.x_axis.z, p.x_axis.w, p.y_axis.x, p.y_axis.z, p.y_axis.w, p.w_axis.x, p.w_axis.y];
        if (p23 + 1.0).abs() > 1e-6
            || p33.abs() > 1e-9
            || skew.iter().any(|e| e.abs() > 1e-9)
            || p00 <= 0.0
            || p11 <= 0.0
        {
            return refuse("not a right-handed perspective projection (clip w = -z, no skew)".into());
        }
        // depth(distance) = p32 / distance - p22, so distance = p32 / (depth + p22).
        let reversed = p32 > 0.0;
        if reversed != convention.reversed_z {
            return refuse(format!(
                "its depth {} with distance, but the depth convention says {}",
                if reversed { "falls" } else { "rises" },
                if convention.reversed_z { "reversed-Z" } else { "standard" }
            ));
        }
        let far_depth = -p22; // depth at infinite distance
        let infinite = (far_depth - if reversed { 0.0 } else { 1.0 }).abs() < 1e-6;
        if infinite != convention.infinite_far {
            return refuse(format!(
                "its far plane is {}, but the depth convention says {}",
                if infinite { "at infinity" } else { "finite" },
                if convention.infinite_far { "infinite" } else { "finite" }
            ));
        }
        let near_depth = if reversed { 1.0 } else { 0.0 };
        let near = p32 / (near_depth + p22);
        if !(near.is_finite() && near > 0.0) {
            return refuse(format!("its near plane ({near} m) is not a positive distance"));
        }
        let angle = |t: f64| t.atan() as f32;
        let fov = Fov {
            left: angle((p20 - 1.0) / p00),
            right: angle((p20 + 1.0) / p00),
            up: angle((p21 + 1.0) / p11),
            down: angle((p21 - 1.0) / p11),
        };
        if let Err(why) = fov.validate() {
            return refuse(why.to_string());
        }
        Ok(Projection { fov, near, depth_offset: p22, depth_numerator: p32 })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_engine_can_live_in_a_multithreaded_host() {
        fn send_sync<T: Send + Sync>() {}
        send_sync::<AoEngine>();
    }
    use crate::stereo::Fov;

    fn fov() -> Fov {
        Fov { left: -0.8, right: 0.7, up: 0.75, down: -0.85 }
    }

    #[test]
    fn vrao_s_own_projection_reads_back_its_field_of_view_and_near() {
        let p = Fov::reversed_z_projection(&fov(), 0.05).as_mat4();
        let read = Projection::of(&p, DepthConvention::REVERSED_INFINITE, "p").unwrap();
        for (a, b) in [(read.fov.left, -0.8), (read.fov.right, 0.7), (read.fov.up, 0.75), (read.fov.down, -0.85)] {
            assert!((a - b).abs() < 1e-6, "{:?}", read.fov);
        }
        assert!((read.near - 0.05).abs() < 1e-9);
        // Reversed-Z infinite: depth = near / distance.
        assert!((read.depth_numerator / (0.01 + read.depth_offset) - 5.0).abs() < 1e-6);
    }

    #[test]
    fn a_standard_finite_projection_maps_its_planes() {
        let p = glam::camera::rh::proj::directx::perspective(1.2, 0.9, 0.1, 100.0);
        let read = Projection::of(&p, DepthConvention::STANDARD_FINITE, "p").unwrap();
        assert!((read.near - 0.1).abs() < 1e-5, "{read:?}");
        let distance = |depth: f64| read.depth_numerator / (depth + read.depth_offset);
        assert!((distance(0.0) - 0.1).abs() < 1e-5);
        assert!((distance(1.0) - 100.0).abs() < 1e-2);
        assert!((read.fov.up - 0.6).abs() < 1e-5 && (read.fov.down + 0.6).abs() < 1e-5);
    }

    #[test]
    fn a_convention_the_projection_contradicts_is_refused() {
        let standard = glam::camera::rh::proj::directx::perspective(1.2, 0.9, 0.1, 100.0);
        let e = Projection::of(&standard, DepthConvention::REVERSED_INFINITE, "p").unwrap_err().to_string();
        assert!(e.contains("reversed-Z"), "{e}");
        let reversed_infinite = glam::camera::rh::proj::directx::perspective_infinite_reverse(1.2, 0.9, 0.1);
        let e = Projection::of(&reversed_infinite, DepthConvention { reversed_z: true, infinite_far: false }, "p")
            .unwrap_err()
            .to_string();
        assert!(e.contains("infinity"), "{e}");
        let orthographic = glam::camera::rh::proj::directx::orthographic(-1.0, 1.0, -1.0, 1.0, 0.1, 10.0);
        assert!(Projection::of(&orthographic, DepthConvention::STANDARD_FINITE, "p").is_err());
    }

    #[test]
    fn a_view_matrix_must_be_rigid() {
        let view =
            glam::camera::rh::view::look_at_mat4(glam::Vec3::new(1.0, 2.0, 3.0), glam::Vec3::ZERO, glam::Vec3::Y);
        let pose = rigid_pose(&view, "v").unwrap();
        assert!((pose.position - glam::DVec3::new(1.0, 2.0, 3.0)).length() < 1e-5);
        let eye = Eye { side: EyeSide::Left, pose, fov: fov() };
        let back = eye.view_from_world().as_mat4();
        assert!(back.abs_diff_eq(view, 1e-5), "{back} vs {view}");
        assert!(rigid_pose(&(view * Mat4::from_scale(glam::Vec3::splat(2.0))), "v").is_err());
        assert!(rigid_pose(&Mat4::from_cols_array(&[f32::NAN; 16]), "v").is_err());
    }
}
