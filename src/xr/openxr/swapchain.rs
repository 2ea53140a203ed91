//! The eye swapchains: colour and (with XR_KHR_composition_layer_depth) depth images the
//! runtime owns, wrapped as wgpu textures, and the blit that fills them from the
//! renderer's 2-layer colour and depth targets.
//!
//! Layout: one 2-layer array swapchain per kind when the runtime accepts one (one
//! acquire/release per kind and frame), otherwise one swapchain per eye.
//!
//! Colour format: vrao's colour target is Rgba8Unorm holding sRGB-encoded values. A
//! plain copy into an sRGB swapchain would be byte-exact, but copies need the same
//! channel order and leave the image in TRANSFER_DST layout, while OpenXR wants it back
//! in COLOR_ATTACHMENT_OPTIMAL at release. So every format goes through a small render
//! pass (shaders/xr_blit.wgsl) that decodes sRGB to linear and lets an sRGB swapchain
//! encode again (exact for 8 bits); a UNORM or float swapchain then holds linear values,
//! which is how OpenXR runtimes read them. sRGB formats are preferred (8 bits per
//! channel without banding), then float16, then UNORM. Depth goes through the same pass
//! (frag_depth), which also leaves it in DEPTH_STENCIL_ATTACHMENT_OPTIMAL.

use super::RuntimeFailure;
use ash::vk;
use ash::vk::Handle as _;
use openxr as xr;
use vrao_ao::plug::{fullscreen_pipeline, Gpu, LayeredTarget};
use wgpu::hal::api::Vulkan as HalVulkan;

/// Colour formats in order of preference (Vulkan format, wgpu format).
const COLOR_FORMATS: [(vk::Format, wgpu::TextureFormat); 5] = [
    (vk::Format::R8G8B8A8_SRGB, wgpu::TextureFormat::Rgba8UnormSrgb),
    (vk::Format::B8G8R8A8_SRGB, wgpu::TextureFormat::Bgra8UnormSrgb),
    (vk::Format::R16G16B16A16_SFLOAT, wgpu::TextureFormat::Rgba16Float),
    (vk::Format::R8G8B8A8_UNORM, wgpu::TextureFormat::Rgba8Unorm),
    (vk::Format::B8G8R8A8_UNORM, wgpu::TextureFormat::Bgra8Unorm),
];

/// Depth formats in order of preference. D24 formats are left out: wgpu's Depth24Plus
/// may stand for another Vulkan format than the runtime's image has.
const DEPTH_FORMATS: [(vk::Format, wgpu::TextureFormat); 2] = [
    (vk::Format::D32_SFLOAT, wgpu::TextureFormat::Depth32Float),
    (vk::Format::D16_UNORM, wgpu::TextureFormat::Depth16Unorm),
];

fn pick(offered: &[u32], table: &[(vk::Format, wgpu::TextureFormat)]) -> Option<(vk::Format, wgpu::TextureFormat)> {
    table.iter().copied().find(|(vk_format, _)| offered.contains(&(vk_format.as_raw() as u32)))
}

/// How the two eyes map onto swapchains.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SwapchainLayout {
    /// One swapchain with two array layers (layer 0 = left eye).
    Array,
    /// One single-layer swapchain per eye.
    PerEye,
}

impl SwapchainLayout {
    /// The swapchain and array layer that hold `eye`.
    fn slot(self, eye: usize) -> (usize, u32) {
        match self {
            SwapchainLayout::Array => (0, eye as u32),
            SwapchainLayout::PerEye => (eye, 0),
        }
    }
}

/// The swapchains of one kind (colour or depth): their images as wgpu textures and a
/// single-layer view per image and layer.
struct Chain {
    swapchains: Vec<xr::Swapchain<xr::Vulkan>>,
    /// [swapchain][image]
    textures: Vec<Vec<wgpu::Texture>>,
    /// [swapchain][image][layer]
    views: Vec<Vec<Vec<wgpu::TextureView>>>,
    vk_format: vk::Format,
    format: wgpu::TextureFormat,
}

impl Chain {
    fn create(
        gpu: &Gpu,
        session: &xr::Session<xr::Vulkan>,
        layout: SwapchainLayout,
        (vk_format, format): (vk::Format, wgpu::TextureFormat),
        (width, height): (u32, u32),
    ) -> xr::Result<Chain> {
        let depth = format.is_depth_stencil_format();
        let (usage, uses) = if depth {
            (xr::SwapchainUsageFlags::DEPTH_STENCIL_ATTACHMENT, wgpu::TextureUses::DEPTH_STENCIL_WRITE)
        } else {
            (xr::SwapchainUsageFlags::COLOR_ATTACHMENT, wgpu::TextureUses::COLOR_TARGET)
        };
        let (count, layers) = match layout {
            SwapchainLayout::Array => (1, 2),
            SwapchainLayout::PerEye => (2, 1),
        };
        let mut chain = Chain { swapchains: Vec::new(), textures: Vec::new(), views: Vec::new(), vk_format, format };
        for _ in 0..count {
            let swapchain = session.create_swapchain(&xr::SwapchainCreateInfo {
                create_flags: xr::SwapchainCreateFlags::EMPTY,
                usage_flags: usage,
                format: vk_format.as_raw() as u32,
                sample_count: 1,
                width,
                height,
                face_count: 1,
                array_size: layers,
                mip_count: 1,
            })?;
            let images = swapchain.enumerate_images()?;
            let label = if depth { "openxr depth swapchain" } else { "openxr colour swapchain" };
            let size = wgpu::Extent3d { width, height, depth_or_array_layers: layers };
            let textures: Vec<wgpu::Texture> = images
                .iter()
                .map(|&image| wrap_image(gpu, vk::Image::from_raw(image), label, size, format, uses))
                .collect();
            let views = textures.iter().map(|texture| vrao_ao::plug::layer_views(texture, label, layers)).collect();
            chain.swapchains.push(swapchain);
            chain.textures.push(textures);
            chain.views.push(views);
        }
        Ok(chain)
    }

    /// xrAcquireSwapchainImage + xrWaitSwapchainImage on every swapchain; the image
    /// index of each.
    fn acquire(&mut self) -> Result<Vec<usize>, FillError> {
        let mut indices = Vec::with_capacity(self.swapchains.len());
        for swapchain in &mut self.swapchains {
            let index = swapchain.acquire_image().map_err(|e| FillError::Xr("xrAcquireSwapchainImage", e))?;
            swapchain.wait_image(xr::Duration::INFINITE).map_err(|e| FillError::Xr("xrWaitSwapchainImage", e))?;
            indices.push(index as usize);
        }
        Ok(indices)
    }

    fn release(&mut self) -> Result<(), FillError> {
        for swapchain in &mut self.swapchains {
            swapchain.release_image().map_err(|e| FillError::Xr("xrReleaseSwapchainImage", e))?;
        }
        Ok(())
    }
}

/// Wraps one swapchain image. The runtime keeps ownership (the drop callback does
/// nothing), and wgpu is told the layout OpenXR hands images over in: colour attachment
/// or depth attachment optimal.
fn wrap_image(
    gpu: &Gpu,
    image: vk::Image,
    label: &str,
    size: wgpu::Extent3d,
    format: wgpu::TextureFormat,
    uses: wgpu::TextureUses,
) -> wgpu::Texture {
    let hal_desc = wgpu::hal::TextureDescriptor {
        label: Some(label),
        size,
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: uses,
        memory_flags: wgpu::hal::MemoryFlags::empty(),
        view_formats: Vec::new(),
    };
    let hal_texture = {
        // SAFETY: the device is the Vulkan device the session was created with.
        let hal_device = unsafe { gpu.device.as_hal::<HalVulkan>() }.expect("the OpenXR device is a Vulkan device");
        // SAFETY: `image` is a swapchain image of this device, created with `size`,
        // `format`, one mip level and one sample; its memory belongs to the runtime.
        unsafe {
            hal_device.texture_from_raw(
                image,
                &hal_desc,
                Some(Box::new(|| {})),
                wgpu::hal::vulkan::TextureMemory::External,
            )
        }
    };
    let desc = wgpu::TextureDescriptor {
        label: Some(label),
        size,
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
        view_formats: &[],
    };
    // SAFETY: the hal texture matches `desc`, and the image is in the layout `uses`
    // stands for whenever the application holds it.
    unsafe { gpu.device.create_texture_from_hal::<HalVulkan>(hal_texture, &desc, uses) }
}

/// The render pipeline that copies one eye of the renderer's colour (sRGB-encoded
/// Rgba8Unorm) and depth into a colour view of any format (decoding to linear; an sRGB
/// view encodes again) and, optionally, a depth view. Public so it can be tested
/// against ordinary textures.
pub struct EyeBlit {
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::RenderPipeline,
    depth: bool,
}

impl EyeBlit {
    /// Builds the pipeline for a `color` swapchain format and, when given, a `depth` one.
    pub fn new(device: &wgpu::Device, color: wgpu::TextureFormat, depth: Option<wgpu::TextureFormat>) -> EyeBlit {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("openxr blit"),
            source: wgpu::ShaderSource::Wgsl(include_str!("../../../shaders/xr_blit.wgsl").into()),
        });
        let texture = |binding, sample_type| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Texture {
                sample_type,
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            },
            count: None,
        };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("openxr blit"),
            entries: &[
                texture(0, wgpu::TextureSampleType::Float { filterable: false }),
                texture(1, wgpu::TextureSampleType::Depth),
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("openxr blit"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let depth_stencil = depth.map(|format| wgpu::DepthStencilState {
            format,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Always),
            stencil: Default::default(),
            bias: Default::default(),
        });
        let fragment = if depth.is_some() { "fs_color_depth" } else { "fs_color" };
        let pipeline = fullscreen_pipeline(
            device,
            "openxr blit",
            &pipeline_layout,
            (&module, fragment),
            color,
            depth_stencil,
            None,
        );
        EyeBlit { layout, pipeline, depth: depth.is_some() }
    }

    /// Records the copy of layer `eye` of `color` and `depth` into `color_view` (and
    /// `depth_view`, which must be given exactly when the blit was made with a depth
    /// format), over `width` × `height` pixels from the top-left.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        color: &LayeredTarget,
        depth: &LayeredTarget,
        eye: usize,
        color_view: &wgpu::TextureView,
        depth_view: Option<&wgpu::TextureView>,
        (width, height): (u32, u32),
    ) {
        assert_eq!(depth_view.is_some(), self.depth, "a depth view exactly when the blit writes depth");
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("openxr blit"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(
                        &color.layer_views[eye.min(color.layers as usize - 1)],
                    ),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(
                        &depth.layer_views[eye.min(depth.layers as usize - 1)],
                    ),
                },
            ],
        });
        let mut pass = vrao_ao::plug::colour_and_depth_pass(
            encoder,
            "openxr swapchain blit",
            (color_view, wgpu::Color::BLACK),
            depth_view,
        );
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.set_viewport(0.0, 0.0, width as f32, height as f32, 0.0, 1.0);
        pass.draw(0..3, 0..1);
    }
}

/// Where one eye's image is in the swapchains, for the projection layer.
#[derive(Clone, Copy, Debug)]
pub(super) struct SubImage {
    pub swapchain: usize,
    pub array_index: u32,
    pub width: u32,
    pub height: u32,
}

/// Colour and depth swapchains for both eyes.
pub(super) struct EyeSwapchains {
    color: Chain,
    depth: Option<Chain>,
    blit: EyeBlit,
    pub layout: SwapchainLayout,
    pub size: (u32, u32),
}

impl EyeSwapchains {
    /// Picks formats from what the session offers and creates the swapchains: one 2-layer
    /// array per kind when the runtime accepts it, otherwise one per eye (or only the
    /// given `layout`). `with_depth` is false when the runtime lacks
    /// XR_KHR_composition_layer_depth.
    pub(super) fn create(
        gpu: &Gpu,
        session: &xr::Session<xr::Vulkan>,
        size: (u32, u32),
        with_depth: bool,
        layout: Option<SwapchainLayout>,
    ) -> Result<EyeSwapchains, RuntimeFailure> {
        let offered = session.enumerate_swapchain_formats().map_err(|e| format!("xrEnumerateSwapchainFormats: {e}"))?;
        let color_format = pick(&offered, &COLOR_FORMATS).ok_or_else(|| {
            format!("the runtime offers no colour swapchain format vrao can fill (offered Vulkan formats {offered:?})")
        })?;
        let depth_format = if with_depth { pick(&offered, &DEPTH_FORMATS) } else { None };
        let mut last_error = None;
        let layouts = match layout {
            Some(layout) => vec![layout],
            None => vec![SwapchainLayout::Array, SwapchainLayout::PerEye],
        };
        for layout in layouts {
            let chains = Chain::create(gpu, session, layout, color_format, size).and_then(|color| {
                let depth = depth_format.map(|format| Chain::create(gpu, session, layout, format, size)).transpose()?;
                Ok((color, depth))
            });
            match chains {
                Ok((color, depth)) => {
                    let blit = EyeBlit::new(&gpu.device, color.format, depth.as_ref().map(|d| d.format));
                    return Ok(EyeSwapchains { color, depth, blit, layout, size });
                }
                Err(e) => {
                    log::info!("OpenXR: {layout:?} swapchains refused ({e}); trying the next layout");
                    last_error = Some(e);
                }
            }
        }
        Err(RuntimeFailure(format!("xrCreateSwapchain: {}", last_error.expect("at least one layout was tried"))))
    }

    pub(super) fn has_depth(&self) -> bool {
        self.depth.is_some()
    }

    /// One line: layout, formats and size.
    pub(super) fn describe(&self) -> String {
        let layout = match self.layout {
            SwapchainLayout::Array => "one 2-layer array swapchain",
            SwapchainLayout::PerEye => "one swapchain per eye",
        };
        let depth = match &self.depth {
            Some(d) => format!(" + depth {:?}", d.vk_format),
            None => " (no depth: the runtime lacks XR_KHR_composition_layer_depth or a depth format)".into(),
        };
        format!("{}x{} per eye, {layout}, colour {:?}{depth}", self.size.0, self.size.1, self.color.vk_format)
    }

    pub(super) fn color_swapchain(&self, index: usize) -> &xr::Swapchain<xr::Vulkan> {
        &self.color.swapchains[index]
    }

    pub(super) fn depth_swapchain(&self, index: usize) -> Option<&xr::Swapchain<xr::Vulkan>> {
        self.depth.as_ref().map(|d| &d.swapchains[index])
    }

    /// Acquires an image of every swapchain, copies both eyes of `color` and `depth`
    /// into them, submits the copy and releases the images (the copy is queued before
    /// the release, on the queue the session was created with). Returns each eye's
    /// sub-image.
    pub(super) fn fill(
        &mut self,
        gpu: &Gpu,
        color: &LayeredTarget,
        depth: &LayeredTarget,
    ) -> Result<[SubImage; 2], FillError> {
        let color_indices = self.color.acquire()?;
        let depth_indices = match self.depth.as_mut().map(Chain::acquire).transpose() {
            Ok(indices) => indices,
            Err(e) => {
                let _ = self.color.release();
                return Err(e);
            }
        };
        let width = color.width.min(self.size.0);
        let height = color.height.min(self.size.1);
        let mut encoder =
            gpu.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("openxr swapchain blit") });
        let mut sub_images = [SubImage { swapchain: 0, array_index: 0, width, height }; 2];
        for (eye, sub_image) in sub_images.iter_mut().enumerate() {
            let (swapchain, layer) = self.layout.slot(eye);
            *sub_image = SubImage { swapchain, array_index: layer, width, height };
            let color_view = &self.color.views[swapchain][color_indices[swapchain]][layer as usize];
            let depth_view = match (&self.depth, &depth_indices) {
                (Some(chain), Some(indices)) => Some(&chain.views[swapchain][indices[swapchain]][layer as usize]),
                _ => None,
            };
            self.blit.record(&gpu.device, &mut encoder, color, depth, eye, color_view, depth_view, (width, height));
        }
        gpu.queue.submit([encoder.finish()]);
        let gpu_error = gpu.take_error();
        let released = self.color.release().and_then(|()| self.depth.as_mut().map(Chain::release).unwrap_or(Ok(())));
        gpu_error.map_err(|e| FillError::Gpu(e.into()))?;
        released?;
        Ok(sub_images)
    }

    /// Destroys the wgpu side of the images (the runtime destroys the images themselves
    /// with the swapchains). Call with the GPU idle.
    pub(super) fn destroy_textures(&mut self) {
        for chain in std::iter::once(&mut self.color).chain(self.depth.as_mut()) {
            chain.views.clear();
            for texture in chain.textures.drain(..).flatten() {
                texture.destroy();
            }
        }
    }
}

/// Why a frame could not be copied into the swapchains.
#[derive(Debug)]
pub(super) enum FillError {
    /// The OpenXR call that failed and its result.
    Xr(&'static str, xr::sys::Result),
    Gpu(crate::error::Error),
}

impl std::fmt::Display for FillError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            FillError::Xr(call, e) => write!(f, "{}", super::xr_call_failed(call, *e)),
            FillError::Gpu(e) => write!(f, "{e}"),
        }
    }
}
