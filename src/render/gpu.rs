//! A wgpu device and queue: made headless for the bake and tests, or
//! taken from the viewer's window (eframe's render state).

use crate::error::{Error, Result};

pub struct Gpu {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    /// The adapter's name and backend, for reports.
    pub adapter: String,
}

impl Gpu {
    /// A device with no window. Any adapter will do; on machines without
    /// a GPU that is a software one (llvmpipe through Vulkan, from Debian's
    /// mesa-vulkan-drivers). Without a desktop session, Mesa's device-select
    /// layer prints a harmless "XDG_RUNTIME_DIR is invalid" error unless
    /// NODEVICE_SELECT=1 is set, as the organtex binary sets it.
    pub fn headless() -> Result<Gpu> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: false,
            compatible_surface: None,
            apply_limit_buckets: false,
        }))
        .map_err(|e| {
            Error::invalid(format!(
                "no GPU adapter found ({e}); on a machine without a GPU install a software \
                 driver (Debian: apt install mesa-vulkan-drivers)"
            ))
        })?;
        let info = adapter.get_info();
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("organtex"),
            required_features: wgpu::Features::empty(),
            required_limits: wgpu::Limits::downlevel_defaults().using_resolution(adapter.limits()),
            ..Default::default()
        }))
        .map_err(|e| Error::invalid(format!("cannot open the GPU device {}: {e}", info.name)))?;
        Ok(Gpu {
            device,
            queue,
            adapter: format!("{} ({:?})", info.name, info.backend),
        })
    }

    /// The viewer's device and queue.
    pub fn from_parts(device: wgpu::Device, queue: wgpu::Queue, adapter: String) -> Gpu {
        Gpu {
            device,
            queue,
            adapter,
        }
    }
}
