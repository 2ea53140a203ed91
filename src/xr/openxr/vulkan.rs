//! The GPU of an OpenXR session, through XR_KHR_vulkan_enable2: the runtime creates the
//! VkInstance and VkDevice (`xrCreateVulkanInstanceKHR`, `xrCreateVulkanDeviceKHR`) from
//! create infos that already name what wgpu-hal needs, adding its own extensions; wgpu
//! then wraps them (`wgpu::hal::vulkan::Instance::from_raw`, `Adapter::device_from_raw`).
//! XR_KHR_vulkan_enable (the first version) is not used: it hands the application a list
//! of device extensions that lavapipe does not have, where enable2 lets the runtime pick.
//!
//! wgpu-hal owns the instance and device it wraps (no drop callback) and destroys them
//! when the last wgpu handle goes, after the OpenXR session: enable2 makes the
//! application the owner of both.

use super::RuntimeFailure;
use ash::vk;
use ash::vk::Handle as _;
use std::ffi::{c_char, CStr};
use vrao_ao::plug::Gpu;
use wgpu::hal::api::Vulkan as HalVulkan;
use wgpu::hal::{ExposedAdapter, OpenDevice};

/// What `xrCreateSession` needs to bind the session to the device.
pub(super) struct Binding {
    pub instance: vk::Instance,
    pub physical_device: vk::PhysicalDevice,
    pub device: vk::Device,
    pub queue_family_index: u32,
}

impl Binding {
    pub(super) fn session_create_info(&self) -> openxr::vulkan::SessionCreateInfo {
        openxr::vulkan::SessionCreateInfo {
            instance: self.instance.as_raw() as usize as _,
            physical_device: self.physical_device.as_raw() as usize as _,
            device: self.device.as_raw() as usize as _,
            queue_family_index: self.queue_family_index,
            queue_index: 0,
        }
    }
}

/// The Vulkan version to create the instance with: what the loader offers, capped at
/// 1.3 (wgpu-hal's ceiling) and at the runtime's maximum.
fn api_version(entry: &ash::Entry, requirements: &openxr::vulkan::Requirements) -> Result<u32, RuntimeFailure> {
    // SAFETY: a plain query of the loader.
    let loader = unsafe { entry.try_enumerate_instance_version() }
        .map_err(|e| format!("vkEnumerateInstanceVersion: {e}"))?
        .unwrap_or(vk::API_VERSION_1_0);
    let max = requirements.max_api_version_supported;
    let runtime_max = vk::make_api_version(0, max.major() as u32, max.minor() as u32, 0);
    let version = loader.min(vk::API_VERSION_1_3).min(runtime_max.max(vk::API_VERSION_1_0));
    let min = requirements.min_api_version_supported;
    let runtime_min = vk::make_api_version(0, min.major() as u32, min.minor() as u32, 0);
    if version < runtime_min {
        return Err(RuntimeFailure(format!(
            "the runtime needs Vulkan {}.{}, the loader offers {}.{}",
            min.major(),
            min.minor(),
            vk::api_version_major(loader),
            vk::api_version_minor(loader)
        )));
    }
    Ok(version)
}

fn names(list: &[&'static CStr]) -> Vec<*const c_char> {
    list.iter().map(|name| name.as_ptr()).collect()
}

/// Creates the Vulkan instance and device through the runtime and wraps them as vrao's
/// `Gpu` (same features, limits and multiview probe as `Gpu::new`). Each failing call's
/// message (a `String`) becomes the [`RuntimeFailure`] through `?`.
pub(super) fn create_gpu(xr: &openxr::Instance, system: openxr::SystemId) -> Result<(Gpu, Binding), RuntimeFailure> {
    // xrGetVulkanGraphicsRequirements2KHR must come before the instance is created.
    let requirements = xr
        .graphics_requirements::<openxr::Vulkan>(system)
        .map_err(|e| format!("xrGetVulkanGraphicsRequirements2KHR: {e}"))?;
    // SAFETY: loads the system's Vulkan loader (libvulkan.so.1), as wgpu itself does.
    let entry = unsafe { ash::Entry::load() }.map_err(|e| format!("no Vulkan loader: {e}"))?;
    let version = api_version(&entry, &requirements)?;
    let flags = wgpu::InstanceFlags::from_build_config().with_env();
    let created = create_vk_instance(xr, system, &entry, version, flags)?;
    let (raw_instance, get_instance_proc_addr) = (created.raw, created.get_instance_proc_addr);
    let vk_instance = vk::Instance::from_raw(raw_instance as usize as u64);
    let (ash_instance, hal_instance) = wrap_instance(&entry, vk_instance, created.extensions, version, flags)?;

    let (raw_physical, physical_device, exposed) = expose_runtime_adapter(xr, system, raw_instance, &hal_instance)?;
    let adapter_name = exposed.info.name.clone();
    // SAFETY: the hal instance is a Vulkan instance.
    let instance = unsafe { wgpu::Instance::from_hal::<HalVulkan>(hal_instance) };
    // SAFETY: the adapter was exposed by the instance just wrapped.
    let adapter = unsafe { instance.create_adapter_from_hal(exposed) };
    let desc = vrao_render::gpu::open::device_descriptor(&adapter);
    let queue_family_index = graphics_queue_family(&ash_instance, physical_device, &adapter_name)?;

    let request = DeviceRequest {
        xr,
        system,
        get_instance_proc_addr,
        raw_physical,
        ash_instance: &ash_instance,
        adapter: &adapter,
        desc: &desc,
        queue_family_index,
    };
    let (open, vk_device) = open_runtime_device(&request)?;
    // SAFETY: the hal device was opened from this adapter with `desc`'s features/limits.
    let (device, queue) = unsafe { adapter.create_device_from_hal(open, &desc) }
        .map_err(|e| format!("{adapter_name} refused a device: {e}"))?;
    let gpu = vrao_render::gpu::open::from_device(instance, adapter, device, queue).map_err(|e| e.to_string())?;
    let binding = Binding { instance: vk_instance, physical_device, device: vk_device, queue_family_index };
    Ok((gpu, binding))
}

/// What `xrCreateVulkanInstanceKHR` returned, with what wrapping it and creating the
/// device on it need.
struct RuntimeInstance {
    /// The instance, as OpenXR spells it.
    raw: openxr::sys::platform::VkInstance,
    /// The instance extensions it was created with (wgpu-hal's desired ones).
    extensions: Vec<&'static CStr>,
    /// The loader's vkGetInstanceProcAddr, as OpenXR spells it.
    get_instance_proc_addr: openxr::sys::platform::VkGetInstanceProcAddr,
}

/// Has the runtime create the Vulkan instance with `version` and the instance extensions
/// wgpu-hal desires (the runtime adds its own).
fn create_vk_instance(
    xr: &openxr::Instance,
    system: openxr::SystemId,
    entry: &ash::Entry,
    version: u32,
    flags: wgpu::InstanceFlags,
) -> Result<RuntimeInstance, RuntimeFailure> {
    let instance_extensions = wgpu::hal::vulkan::Instance::desired_extensions(entry, version, flags)
        .map_err(|e| format!("Vulkan instance extensions: {e}"))?;
    let instance_extension_names = names(&instance_extensions);
    let app_info = vk::ApplicationInfo::default()
        .application_name(c"vrao")
        .application_version(1)
        .engine_name(c"vrao")
        .engine_version(1)
        .api_version(version);
    let instance_info = vk::InstanceCreateInfo::default()
        .application_info(&app_info)
        .enabled_extension_names(&instance_extension_names);
    // SAFETY: the two function-pointer types have the same ABI (instance handle and name
    // in, optional function pointer out); openxr-sys spells the handle as a pointer.
    let get_instance_proc_addr: openxr::sys::platform::VkGetInstanceProcAddr =
        unsafe { std::mem::transmute(entry.static_fn().get_instance_proc_addr) };

    // SAFETY: the create info and everything it points to live until the call returns;
    // the graphics requirements were queried before (in `create_gpu`), as enable2 requires.
    let raw_instance =
        unsafe { xr.create_vulkan_instance(system, get_instance_proc_addr, &instance_info as *const _ as *const _) }
            .map_err(|e| format!("xrCreateVulkanInstanceKHR: {e}"))?
            .map_err(|e| {
                format!("xrCreateVulkanInstanceKHR: vkCreateInstance returned {:?}", vk::Result::from_raw(e))
            })?;
    Ok(RuntimeInstance { raw: raw_instance, extensions: instance_extensions, get_instance_proc_addr })
}

/// Loads the runtime's Vulkan instance into ash and hands it to wgpu-hal, which owns it
/// from then on.
fn wrap_instance(
    entry: &ash::Entry,
    vk_instance: vk::Instance,
    instance_extensions: Vec<&'static CStr>,
    version: u32,
    flags: wgpu::InstanceFlags,
) -> Result<(ash::Instance, wgpu::hal::vulkan::Instance), RuntimeFailure> {
    // SAFETY: the instance was just created through this entry's vkGetInstanceProcAddr.
    let ash_instance = unsafe { ash::Instance::load(entry.static_fn(), vk_instance) };
    // SAFETY: created from `entry` with `version` and a superset of desired_extensions();
    // no drop callback: wgpu-hal owns the instance from here on.
    let hal_instance = unsafe {
        wgpu::hal::vulkan::Instance::from_raw(
            entry.clone(),
            ash_instance.clone(),
            version,
            0,
            None,
            instance_extensions,
            flags,
            wgpu::MemoryBudgetThresholds::default(),
            false,
            None,
        )
    }
    .map_err(|e| format!("wrapping the runtime's Vulkan instance: {e}"))?;
    Ok((ash_instance, hal_instance))
}

/// Asks the runtime which physical device to use and exposes it as a wgpu-hal adapter;
/// returns it as OpenXR and as ash spell it, and the adapter.
fn expose_runtime_adapter(
    xr: &openxr::Instance,
    system: openxr::SystemId,
    raw_instance: openxr::sys::platform::VkInstance,
    hal_instance: &wgpu::hal::vulkan::Instance,
) -> Result<(openxr::sys::platform::VkPhysicalDevice, vk::PhysicalDevice, ExposedAdapter<HalVulkan>), RuntimeFailure> {
    // SAFETY: the instance came from xrCreateVulkanInstanceKHR for this system.
    let raw_physical = unsafe { xr.vulkan_graphics_device(system, raw_instance) }
        .map_err(|e| format!("xrGetVulkanGraphicsDevice2KHR: {e}"))?;
    let physical_device = vk::PhysicalDevice::from_raw(raw_physical as usize as u64);
    let exposed = hal_instance
        .expose_adapter(physical_device)
        .ok_or_else(|| "wgpu cannot use the runtime's Vulkan device (too old or missing features)".to_string())?;
    Ok((raw_physical, physical_device, exposed))
}

/// The index of the first queue family of `physical_device` that does graphics and compute.
fn graphics_queue_family(
    ash_instance: &ash::Instance,
    physical_device: vk::PhysicalDevice,
    adapter_name: &str,
) -> Result<u32, RuntimeFailure> {
    // One queue, from the first family that does graphics and compute (wgpu's own device
    // uses one such queue too).
    // SAFETY: a query of a valid physical device.
    let families = unsafe { ash_instance.get_physical_device_queue_family_properties(physical_device) };
    let queue_family_index = families
        .iter()
        .position(|f| f.queue_flags.contains(vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE))
        .ok_or_else(|| format!("{adapter_name} has no graphics and compute queue"))?
        as u32;
    Ok(queue_family_index)
}

/// What creating the runtime's Vulkan device needs.
struct DeviceRequest<'a> {
    xr: &'a openxr::Instance,
    system: openxr::SystemId,
    get_instance_proc_addr: openxr::sys::platform::VkGetInstanceProcAddr,
    /// The physical device the runtime chose, as OpenXR spells it.
    raw_physical: openxr::sys::platform::VkPhysicalDevice,
    ash_instance: &'a ash::Instance,
    adapter: &'a wgpu::Adapter,
    desc: &'a wgpu::DeviceDescriptor<'static>,
    queue_family_index: u32,
}

/// Has the runtime create the Vulkan device for the adapter and opens it as a wgpu-hal
/// device (which owns it from then on); returns that and the device's handle.
fn open_runtime_device(request: &DeviceRequest) -> Result<(OpenDevice<HalVulkan>, vk::Device), RuntimeFailure> {
    let DeviceRequest { ash_instance, adapter, desc, queue_family_index, .. } = *request;
    // SAFETY: the adapter is a Vulkan adapter.
    let hal_adapter = unsafe { adapter.as_hal::<HalVulkan>() }
        .ok_or_else(|| "the OpenXR adapter is not a Vulkan adapter".to_string())?;
    let device_extensions = hal_adapter.required_device_extensions(desc.required_features);
    let raw_device = create_vk_device(request, &hal_adapter, &device_extensions)?;
    let vk_device = vk::Device::from_raw(raw_device as usize as u64);
    // SAFETY: the device was created on this instance.
    let ash_device = unsafe { ash::Device::load(ash_instance.fp_v1_0(), vk_device) };
    // SAFETY: created from this adapter with queue family `queue_family_index`, the
    // required extensions (the runtime may add more) and physical_device_features();
    // no drop callback: wgpu-hal owns the device.
    let open = unsafe {
        hal_adapter.device_from_raw(
            ash_device,
            None,
            &device_extensions,
            desc.required_features,
            &desc.required_limits,
            &desc.memory_hints,
            queue_family_index,
            0,
        )
    }
    .map_err(|e| format!("wrapping the runtime's Vulkan device: {e}"))?;
    Ok((open, vk_device))
}

/// Has the runtime create the Vulkan device: one queue of the request's family, the
/// required `device_extensions` and the adapter's features for them.
fn create_vk_device(
    request: &DeviceRequest,
    hal_adapter: &wgpu::hal::vulkan::Adapter,
    device_extensions: &[&'static CStr],
) -> Result<openxr::sys::platform::VkDevice, RuntimeFailure> {
    let DeviceRequest { xr, system, get_instance_proc_addr, raw_physical, desc, queue_family_index, .. } = *request;
    let mut device_features = hal_adapter.physical_device_features(device_extensions, desc.required_features);
    let device_extension_names = names(device_extensions);
    let priorities = [1.0f32];
    let queues =
        [vk::DeviceQueueCreateInfo::default().queue_family_index(queue_family_index).queue_priorities(&priorities)];
    let device_info = device_features.add_to_device_create(
        vk::DeviceCreateInfo::default().queue_create_infos(&queues).enabled_extension_names(&device_extension_names),
    );
    // SAFETY: the create info and its feature chain live until the call returns; the
    // physical device is the one the runtime chose.
    let raw_device = unsafe {
        xr.create_vulkan_device(system, get_instance_proc_addr, raw_physical, &device_info as *const _ as *const _)
    }
    .map_err(|e| format!("xrCreateVulkanDeviceKHR: {e}"))?
    .map_err(|e| format!("xrCreateVulkanDeviceKHR: vkCreateDevice returned {:?}", vk::Result::from_raw(e)))?;
    Ok(raw_device)
}
