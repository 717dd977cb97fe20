//! A wgpu device and queue: made headless for the bake and tests, or
//! taken from the viewer's window (eframe's render state).
//!
//! wgpu's default answer to a device, validation or out-of-memory error is
//! a panic. Here every error is caught instead: work that can fail runs in
//! `Gpu::scoped`, which turns what its error scopes catch into an
//! `organtex::Error`, and anything raised outside a scope is kept by the
//! device's uncaptured-error handler for `Gpu::take_error`.

use std::sync::{Arc, Mutex};

use crate::error::{Error, Result};

/// Environment switch: the device's largest 2D texture side, below the
/// adapter's own. The preview then cannot be drawn, which is how tests
/// force a real GPU failure on any machine.
pub const MAX_TEXTURE_ENV: &str = "ORGANTEX_GPU_MAX_TEXTURE";

pub struct Gpu {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    /// The adapter's name and backend, for reports.
    pub adapter: String,
    /// Whether a texture may be viewed in a format other than its own
    /// (sRGB pixels as plain bytes). GL adapters lack it.
    pub view_formats: bool,
    /// A software adapter (llvmpipe, lavapipe): costly filtering is left
    /// off where frames must be interactive.
    pub software: bool,
    /// Errors raised outside any scope, oldest first.
    uncaptured: Arc<Mutex<Vec<String>>>,
}

impl Gpu {
    /// A device with no window. Any adapter will do: Vulkan or GL,
    /// whichever `WGPU_BACKEND` (`vulkan`, `gl`) allows and the machine
    /// has; on machines without a GPU that is a software one (Mesa's
    /// llvmpipe). Without a desktop session, Mesa's device-select Vulkan
    /// layer prints a harmless "XDG_RUNTIME_DIR is invalid" error unless
    /// NODEVICE_SELECT=1 is set, as the organtex binary sets it.
    pub fn headless() -> Result<Gpu> {
        Gpu::headless_on(wgpu::InstanceDescriptor::new_without_display_handle_from_env())
    }

    /// A device with no window on one of `backends` only (tests that
    /// compare Vulkan's picture with GL's).
    pub fn headless_with(backends: wgpu::Backends) -> Result<Gpu> {
        let mut instance = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
        instance.backends = backends;
        Gpu::headless_on(instance)
    }

    fn headless_on(descriptor: wgpu::InstanceDescriptor) -> Result<Gpu> {
        let backends = descriptor.backends;
        let instance = wgpu::Instance::new(descriptor);
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: false,
            compatible_surface: None,
            apply_limit_buckets: false,
        }))
        .map_err(|e| {
            Error::invalid(format!(
                "no GPU adapter found for {backends:?} ({e}); on a machine without a GPU \
                 install a software driver (Debian: apt install libegl1 libgl1-mesa-dri \
                 for GL, or mesa-vulkan-drivers for Vulkan)"
            ))
        })?;
        let info = adapter.get_info();
        let mut limits = wgpu::Limits::downlevel_defaults().using_resolution(adapter.limits());
        if let Some(side) = std::env::var(MAX_TEXTURE_ENV)
            .ok()
            .and_then(|v| v.parse::<u32>().ok())
        {
            limits.max_texture_dimension_2d = limits.max_texture_dimension_2d.min(side);
        }
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("organtex"),
            required_features: wgpu::Features::empty(),
            required_limits: limits,
            ..Default::default()
        }))
        .map_err(|e| Error::invalid(format!("cannot open the GPU device {}: {e}", info.name)))?;
        Ok(Gpu::from_parts(device, queue, &adapter))
    }

    /// A device and queue made elsewhere (the viewer's, by eframe), with
    /// the adapter they came from.
    pub fn from_parts(device: wgpu::Device, queue: wgpu::Queue, adapter: &wgpu::Adapter) -> Gpu {
        let info = adapter.get_info();
        let uncaptured = Arc::new(Mutex::new(Vec::new()));
        let sink = uncaptured.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            if let Ok(mut list) = sink.lock() {
                list.push(describe(&e));
            }
        }));
        Gpu {
            device,
            queue,
            adapter: format!("{} ({:?})", info.name, info.backend),
            view_formats: adapter
                .get_downlevel_capabilities()
                .flags
                .contains(wgpu::DownlevelFlags::VIEW_FORMATS),
            software: info.device_type == wgpu::DeviceType::Cpu,
            uncaptured,
        }
    }

    /// Run `work` with every kind of GPU error caught: a validation,
    /// out-of-memory or internal error it raises becomes an `Err` naming
    /// the first one, and so does one raised earlier outside any scope.
    pub fn scoped<T>(&self, work: impl FnOnce() -> Result<T>) -> Result<T> {
        let scopes = [
            wgpu::ErrorFilter::Validation,
            wgpu::ErrorFilter::OutOfMemory,
            wgpu::ErrorFilter::Internal,
        ]
        .map(|f| self.device.push_error_scope(f));
        let result = work();
        // Scopes pop in reverse order of their pushing.
        let mut caught = None;
        for scope in scopes.into_iter().rev() {
            if let Some(e) = pollster::block_on(scope.pop()) {
                caught.get_or_insert(describe(&e));
            }
        }
        self.take_error()?;
        match caught {
            Some(msg) => Err(Error::invalid(format!(
                "GPU error on {}: {msg}",
                self.adapter
            ))),
            None => result,
        }
    }

    /// The first error the device raised outside any scope since the last
    /// call, if any.
    pub fn take_error(&self) -> Result<()> {
        // A poisoned list still holds the errors (the handler only pushes).
        let mut list = self.uncaptured.lock().unwrap_or_else(|p| p.into_inner());
        let first = list.drain(..).next();
        drop(list);
        match first {
            Some(msg) => Err(Error::invalid(format!(
                "GPU error on {}: {msg}",
                self.adapter
            ))),
            None => Ok(()),
        }
    }
}

/// One line for a wgpu error: its description with the chain of causes
/// (wgpu's own text spans several lines).
fn describe(e: &wgpu::Error) -> String {
    let mut text = match e {
        wgpu::Error::OutOfMemory { .. } => "out of GPU memory".to_string(),
        wgpu::Error::Validation { description, .. } | wgpu::Error::Internal { description, .. } => {
            description.clone()
        }
    };
    let mut source = std::error::Error::source(e);
    while let Some(s) = source {
        let line = s.to_string();
        if !text.contains(&line) {
            text.push_str(": ");
            text.push_str(&line);
        }
        source = s.source();
    }
    text.split_whitespace().collect::<Vec<_>>().join(" ")
}
