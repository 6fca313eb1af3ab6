//! Opening a GPU device without a window, and reading GPU buffers back.

use crate::RenderError;

/// A wgpu device and queue with the adapter they came from.
///
/// [`GpuContext::headless`] opens its own; the editor instead passes eframe's device and queue
/// to [`crate::Renderer::new`] directly.
pub struct GpuContext {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub adapter_info: wgpu::AdapterInfo,
}

impl GpuContext {
    /// Opens the adapter wgpu prefers (a real GPU if there is one, otherwise lavapipe, the CPU
    /// Vulkan driver), with that adapter's limits so large meshes fit.
    ///
    /// # Errors
    /// [`RenderError::NoAdapter`] (with a note on what to install) when wgpu finds no adapter;
    /// [`RenderError::RequestDevice`] when the adapter refuses to open a device.
    pub fn headless() -> Result<Self, RenderError> {
        // Vulkan/Metal/DX12 (lavapipe is Vulkan); `WGPU_BACKEND` overrides.
        let mut descriptor = wgpu::InstanceDescriptor::new_without_display_handle();
        descriptor.backends = wgpu::Backends::PRIMARY;
        let instance = wgpu::Instance::new(descriptor.with_env());
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: false,
            compatible_surface: None,
        }))
        .map_err(|err| RenderError::NoAdapter(err.to_string()))?;
        let adapter_info = adapter.get_info();
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("keyrig headless device"),
            required_features: wgpu::Features::empty(),
            required_limits: adapter.limits(),
            ..Default::default()
        }))
        .map_err(|err| RenderError::RequestDevice {
            adapter: adapter_info.name.clone(),
            message: err.to_string(),
        })?;
        Ok(GpuContext { device, queue, adapter_info })
    }

    /// "name (backend, device type)", for logs and benchmark reports.
    #[must_use]
    pub fn adapter_summary(&self) -> String {
        format!(
            "{} ({:?}, {:?}, driver {} {})",
            self.adapter_info.name,
            self.adapter_info.backend,
            self.adapter_info.device_type,
            self.adapter_info.driver,
            self.adapter_info.driver_info
        )
    }
}

/// Copies `size` bytes of `buffer` (which needs `COPY_SRC`) into a new `Vec`, waiting for the
/// GPU to finish everything submitted before.
///
/// # Errors
/// [`RenderError::Gpu`] when mapping fails or the device is lost.
pub fn read_buffer(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    buffer: &wgpu::Buffer,
    size: u64,
) -> Result<Vec<u8>, RenderError> {
    let staging = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("keyrig readback"),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder =
        device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("readback") });
    encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, size);
    queue.submit([encoder.finish()]);
    map_and_read(device, &staging)
}

/// Maps a `MAP_READ` buffer, waits, and copies its whole contents out.
pub(crate) fn map_and_read(device: &wgpu::Device, staging: &wgpu::Buffer) -> Result<Vec<u8>, RenderError> {
    let (sender, receiver) = std::sync::mpsc::channel();
    staging.slice(..).map_async(wgpu::MapMode::Read, move |result| {
        // The receiver lives until `recv` below returns; a send error cannot happen.
        let _ = sender.send(result);
    });
    device.poll(wgpu::PollType::wait_indefinitely()).map_err(|err| RenderError::Gpu(err.to_string()))?;
    receiver
        .recv()
        .map_err(|err| RenderError::Gpu(format!("buffer mapping callback never ran: {err}")))?
        .map_err(|err| RenderError::Gpu(format!("mapping a readback buffer failed: {err}")))?;
    let bytes = staging.slice(..).get_mapped_range().to_vec();
    staging.unmap();
    Ok(bytes)
}

/// Runs `f` inside a validation + out-of-memory error scope and turns any wgpu error it raised
/// into [`RenderError::Gpu`] instead of wgpu's default panic handler.
pub(crate) fn with_error_scope<T>(device: &wgpu::Device, f: impl FnOnce() -> T) -> Result<T, RenderError> {
    let oom = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let validation = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let value = f();
    let validation_error = pollster::block_on(validation.pop());
    let oom_error = pollster::block_on(oom.pop());
    if let Some(err) = validation_error.or(oom_error) {
        return Err(RenderError::Gpu(err.to_string()));
    }
    Ok(value)
}
