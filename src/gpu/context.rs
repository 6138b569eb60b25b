//! The wgpu device: headless adapter selection and the features geocull needs.

use super::depth_read::{DepthReadback, DepthReader};
use super::readback::ReadbackTexture;
use crate::error::{Error, Interrupt, Result};
use std::any::{Any, TypeId};
use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{mpsc, Arc, Mutex, Weak};

/// How often [`GpuContext::wait_interruptible`] polls the device for finished work.
const WAIT_STEP: std::time::Duration = std::time::Duration::from_millis(1);

/// What a user should do when no adapter is found (no GPU here is normal: lavapipe renders on CPU).
pub const INSTALL_HINT: &str = "install a Vulkan driver; on Debian/Ubuntu without a GPU: \
    `apt-get install libvulkan1 mesa-vulkan-drivers` (Mesa's lavapipe renders on the CPU)";

/// A device and what is built once for it, shared by every [`GpuContext`] opened with the same
/// backends and optional features while any of them lives ([`GpuContext::new`]).
struct Shared {
    device: wgpu::Device,
    queue: wgpu::Queue,
    info: wgpu::AdapterInfo,
    limits: wgpu::Limits,
    timestamps: bool,
    features: wgpu::Features,
    errors: Arc<Mutex<Vec<String>>>,
    depth_copies: bool,
    depth_reader: Arc<DepthReader>,
    /// Objects built once per device ([`GpuContext::per_device`]), by type.
    objects: Mutex<HashMap<TypeId, Arc<dyn Any + Send + Sync>>>,
    /// The device's number among those this process opened (the tests tell devices apart by it).
    #[cfg_attr(not(test), allow(dead_code))]
    serial: u64,
}

static OPENED: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

/// The process that opened this process's first device (0: none yet). A process forked from one
/// that had opened a device inherits the driver's state without its threads: opening a device
/// there crashes at random (lavapipe: heap corruption in about one fork in four), so it is refused.
static DEVICE_PROCESS: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);

/// The devices open in this process, by (backends asked for, optional features) and the id of
/// the process that opened them: a process forked from one that holds a device inherits the
/// entry but not the driver's threads, so it must open a device of its own.
#[allow(clippy::type_complexity)]
static DEVICES: Mutex<Vec<((wgpu::Backends, wgpu::Features, u32), Weak<Shared>)>> = Mutex::new(Vec::new());

/// One user of a device (a renderer): the device's handles, shared with every other context on
/// it, and this user's own state of interrupted submissions.
pub struct GpuContext {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub info: wgpu::AdapterInfo,
    pub limits: wgpu::Limits,
    pub timestamps: bool,
    /// The features the device was opened with.
    pub features: wgpu::Features,
    /// Errors the device reported outside an error scope, taken after each frame (by whichever
    /// context on the device takes them first: they are the device's).
    errors: Arc<Mutex<Vec<String>>>,
    /// Whether depth textures can be copied into buffers (downlevel flag
    /// DEPTH_TEXTURE_AND_BUFFER_COPIES: Vulkan yes, GL no).
    pub depth_copies: bool,
    /// Reads depth textures back through a shader where they cannot be copied.
    depth_reader: Arc<DepthReader>,
    /// Keeps the device's shared entry alive.
    shared: Arc<Shared>,
    /// A submission abandoned by an interrupt, still running on its worker thread (see
    /// [`GpuContext::submit_and_wait`]): the next one waits for it.
    pending: Mutex<Option<mpsc::Receiver<Result<()>>>>,
    /// A wait was abandoned by an interrupt while the GPU still ran the submission.
    abandoned: AtomicBool,
    /// The GL submission thread, started on first use (see [`GpuContext::submit_and_wait`]).
    #[allow(clippy::type_complexity)]
    submitter: Mutex<Option<mpsc::Sender<(wgpu::CommandBuffer, mpsc::Sender<Result<()>>)>>>,
}

/// The environment variable that `backend = "auto"` honours: set to `vulkan`, `gl`, `metal` or
/// `dx12` it chooses that backend for every renderer opened with `"auto"` (e.g. a whole test run on
/// GL: `GEOCULL_BACKEND=gl pytest`); unset, empty or `auto` it leaves the choice to geocull.
pub const BACKEND_ENV: &str = "GEOCULL_BACKEND";

/// The backend a renderer opens: `backend`, or for `"auto"` the value of [`BACKEND_ENV`] if set.
/// Returns the name used in messages and the wgpu backends to enumerate.
fn resolve_backend(backend: &str) -> Result<(String, wgpu::Backends)> {
    if backend == "auto" {
        if let Ok(env) = std::env::var(BACKEND_ENV) {
            let env = env.trim().to_ascii_lowercase();
            if !env.is_empty() {
                let b = parse_backends(&env).map_err(|e| match e {
                    Error::Input { msg, .. } => crate::error::input_err(BACKEND_ENV, msg),
                    e => e,
                })?;
                return Ok((format!("{env} (from {BACKEND_ENV})"), b));
            }
        }
    }
    Ok((backend.to_string(), parse_backends(backend)?))
}

fn parse_backends(backend: &str) -> Result<wgpu::Backends> {
    Ok(match backend {
        "auto" => wgpu::Backends::VULKAN | wgpu::Backends::GL | wgpu::Backends::METAL | wgpu::Backends::DX12,
        "vulkan" => wgpu::Backends::VULKAN,
        "gl" => wgpu::Backends::GL,
        "metal" => wgpu::Backends::METAL,
        "dx12" => wgpu::Backends::DX12,
        _ => {
            return Err(crate::error::input_err(
                "backend",
                format!(
                    "unknown backend {backend:?}; expected one of \"auto\", \"vulkan\", \"gl\", \"metal\", \"dx12\""
                ),
            ))
        }
    })
}

impl GpuContext {
    /// A context on a device of `backend`, with the features geocull always needs plus those of
    /// `optional` that the adapter has (strategies check for theirs before use).
    ///
    /// The device is opened once per process for each (resolved backends, `optional`) and shared
    /// by every context asking for the same while any of them lives: on a CPU adapter a device
    /// costs its driver's pipelines, their compiled code and its rasteriser's bins, about 250 MiB
    /// on lavapipe once it has drawn a large frame, which a second renderer then does not pay
    /// again. Each context keeps its own interrupted-submission state.
    pub fn new(backend: &str, optional: wgpu::Features) -> Result<Self> {
        let (name, backends) = resolve_backend(backend)?;
        let key = (backends, optional, std::process::id());
        if let p @ 1.. = DEVICE_PROCESS.load(Ordering::Relaxed) {
            if p != key.2 {
                return Err(Error::Device(format!(
                    "this process was forked from process {p}, which had opened a graphics device: the driver's \
                     threads do not survive fork() and a device opened here may crash; create renderers in worker \
                     processes started with multiprocessing's \"spawn\" or \"forkserver\" method (scenes, \
                     cameras and volumes pickle), or before the parent opens one"
                )));
            }
        }
        let shared = {
            let mut devices = DEVICES.lock().unwrap_or_else(|p| p.into_inner());
            // Entries of a parent process (before a fork) are dropped without dropping their devices.
            devices.retain(|((_, _, pid), w)| *pid == key.2 && w.strong_count() > 0);
            match devices.iter().find(|(k, _)| *k == key).and_then(|(_, w)| w.upgrade()) {
                Some(s) => s,
                None => {
                    let s = Arc::new(Self::open(&name, backends, optional)?);
                    DEVICE_PROCESS.store(key.2, Ordering::Relaxed);
                    devices.push((key, Arc::downgrade(&s)));
                    s
                }
            }
        };
        Ok(Self {
            device: shared.device.clone(),
            queue: shared.queue.clone(),
            info: shared.info.clone(),
            limits: shared.limits.clone(),
            timestamps: shared.timestamps,
            features: shared.features,
            errors: shared.errors.clone(),
            depth_copies: shared.depth_copies,
            depth_reader: shared.depth_reader.clone(),
            shared,
            pending: Mutex::new(None),
            abandoned: AtomicBool::new(false),
            submitter: Mutex::new(None),
        })
    }

    /// The object of type `T` built once for this context's device by `make` (pipelines and
    /// layouts every user of the device can share), built on first request. `make` runs under the
    /// device's lock: it must not ask for another per-device object.
    pub fn per_device<T: Send + Sync + 'static>(&self, make: impl FnOnce(&wgpu::Device) -> T) -> Arc<T> {
        let mut objects = self.shared.objects.lock().unwrap_or_else(|p| p.into_inner());
        let entry = objects.entry(TypeId::of::<T>()).or_insert_with(|| Arc::new(make(&self.device)));
        entry.clone().downcast::<T>().expect("keyed by its type")
    }

    /// The number of this context's device among those the process opened: equal for contexts
    /// that share it.
    #[cfg(test)]
    pub fn device_serial(&self) -> u64 {
        self.shared.serial
    }

    /// Opens a device (see [`GpuContext::new`]).
    fn open(backend: &str, backends: wgpu::Backends, optional: wgpu::Features) -> Result<Shared> {
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
        desc.backends = backends;
        let instance = wgpu::Instance::new(desc);
        // Prefer a real GPU, then any adapter (lavapipe / llvmpipe on CPU-only machines); among
        // the enumerated ones prefer Vulkan, which has every feature we use.
        let mut adapters = pollster::block_on(instance.enumerate_adapters(backends));
        adapters.sort_by_key(|a| {
            let i = a.get_info();
            let kind = match i.device_type {
                wgpu::DeviceType::DiscreteGpu => 0,
                wgpu::DeviceType::IntegratedGpu => 1,
                wgpu::DeviceType::VirtualGpu => 2,
                wgpu::DeviceType::Cpu => 3,
                wgpu::DeviceType::Other => 4,
            };
            let has_features = a.features().contains(wgpu::Features::INDIRECT_FIRST_INSTANCE);
            (!has_features as u8, kind, (i.backend != wgpu::Backend::Vulkan) as u8)
        });
        let adapter = adapters.into_iter().next().ok_or_else(|| {
            Error::Device(format!("no graphics adapter found for backend {backend:?}; {INSTALL_HINT}"))
        })?;
        let info = adapter.get_info();
        let available = adapter.features();
        let needed = wgpu::Features::INDIRECT_FIRST_INSTANCE;
        if !available.contains(needed) {
            return Err(Error::Device(format!(
                "adapter {} ({:?}) lacks INDIRECT_FIRST_INSTANCE, which geocull's tile draws need; use backend=\"vulkan\" ({INSTALL_HINT})",
                info.name, info.backend
            )));
        }
        let timestamps = available.contains(wgpu::Features::TIMESTAMP_QUERY);
        // Where the adapter allows it (Vulkan, e.g. lavapipe), vertex and index buffers are
        // written in place at creation instead of through a staging copy: on a CPU adapter GPU
        // memory is host memory, and the staging copy doubled the peak memory of an upload.
        let mappable = available & wgpu::Features::MAPPABLE_PRIMARY_BUFFERS;
        let features = needed
            | mappable
            | (optional & available)
            | if timestamps { wgpu::Features::TIMESTAMP_QUERY } else { wgpu::Features::empty() };
        let limits = adapter.limits();
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("geocull"),
            required_features: features,
            required_limits: limits.clone(),
            experimental_features: wgpu::ExperimentalFeatures::disabled(),
            memory_hints: wgpu::MemoryHints::Performance,
            trace: wgpu::Trace::Off,
        }))
        .map_err(|e| Error::Device(format!("could not open device {}: {e}; {INSTALL_HINT}", info.name)))?;
        let errors = Arc::new(Mutex::new(Vec::new()));
        let sink = errors.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            sink.lock().unwrap().push(e.to_string());
        }));
        let depth_copies =
            adapter.get_downlevel_capabilities().flags.contains(wgpu::DownlevelFlags::DEPTH_TEXTURE_AND_BUFFER_COPIES);
        let depth_reader = Arc::new(DepthReader::new(&device));
        Ok(Shared {
            device,
            queue,
            info,
            limits,
            timestamps,
            features,
            errors,
            depth_copies,
            depth_reader,
            objects: Mutex::new(HashMap::new()),
            serial: OPENED.fetch_add(1, Ordering::Relaxed),
        })
    }

    /// Returns the first device error reported since the last call, as an Error.
    pub fn take_error(&self) -> Result<()> {
        let mut errs = self.errors.lock().unwrap();
        if errs.is_empty() {
            return Ok(());
        }
        let msg = errs.join("; ");
        errs.clear();
        Err(Error::Device(format!("the GPU driver rejected the frame: {msg}")))
    }

    pub fn wait(&self) -> Result<()> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map(|_| ())
            .map_err(|e| Error::Device(format!("waiting for the GPU failed: {e}")))
    }

    /// Submits `cb` and waits for the GPU to finish it, polling `interrupt` every
    /// `Interrupt::POLL` (without a hook: a plain submit and wait).
    ///
    /// On GL (llvmpipe) `submit` itself does the frame's vertex work and returns only when it is
    /// nearly done, so no wait after it could be interrupted: there, when `long` says the work may
    /// take long (the caller's estimate, e.g. millions of triangles), the submission runs on a
    /// worker thread (one per context, started on first use) while this thread polls. Not for
    /// short work: moving the GL context between threads costs 1-7 ms per frame on llvmpipe.
    /// On `Err(Interrupted)` the GPU (or the worker) finishes the abandoned work on its own, and
    /// the next [`finish_pending`](Self::finish_pending) (called at the start of every frame)
    /// waits for it.
    pub fn submit_and_wait(&self, cb: wgpu::CommandBuffer, interrupt: &Interrupt, long: bool) -> Result<()> {
        if !interrupt.is_set() {
            self.queue.submit([cb]);
            return self.wait();
        }
        self.finish_pending(interrupt)?;
        if self.info.backend != wgpu::Backend::Gl || !long {
            self.queue.submit([cb]);
            return self.wait_interruptible(interrupt);
        }
        let (tx, rx) = mpsc::channel();
        let mut worker = self.submitter.lock().unwrap_or_else(|p| p.into_inner());
        if worker.is_none() {
            let (jobs, inbox) = mpsc::channel::<(wgpu::CommandBuffer, mpsc::Sender<Result<()>>)>();
            let (queue, device) = (self.queue.clone(), self.device.clone());
            std::thread::Builder::new()
                .name("geocull-submit".into())
                .spawn(move || {
                    for (cb, done) in inbox {
                        queue.submit([cb]);
                        let r = device
                            .poll(wgpu::PollType::wait_indefinitely())
                            .map(|_| ())
                            .map_err(|e| Error::Device(format!("waiting for the GPU failed: {e}")));
                        let _ = done.send(r);
                    }
                })
                .map_err(|e| Error::Device(format!("could not start a thread to submit GPU work: {e}")))?;
            *worker = Some(jobs);
        }
        worker
            .as_ref()
            .unwrap()
            .send((cb, tx))
            .map_err(|_| Error::Device("the GPU submission thread stopped".into()))?;
        drop(worker);
        self.await_worker(rx, interrupt)
    }

    /// [`wait`](Self::wait) for the work submitted so far, polling `interrupt` every
    /// `Interrupt::POLL`. It polls without waiting (every [`WAIT_STEP`]) for the queue's
    /// work-done callback instead of waiting with a timeout: in wgpu-core 30, a wait that times
    /// out while another thread polls or submits on the same device can trip an assertion in
    /// `Device::maintain` (gfx-rs/wgpu#9958, fixed upstream after 30.0.2), which renderers of
    /// one process share and `cargo test` hit.
    fn wait_interruptible(&self, interrupt: &Interrupt) -> Result<()> {
        let done = Arc::new(AtomicBool::new(false));
        let flag = done.clone();
        self.queue.on_submitted_work_done(move || flag.store(true, Ordering::Release));
        let mut checked = std::time::Instant::now();
        loop {
            if let Err(e) = self.device.poll(wgpu::PollType::Poll) {
                return Err(Error::Device(format!("waiting for the GPU failed: {e}")));
            }
            if done.load(Ordering::Acquire) {
                self.abandoned.store(false, Ordering::Relaxed);
                return Ok(());
            }
            if checked.elapsed() >= Interrupt::POLL {
                checked = std::time::Instant::now();
                if let Err(e) = interrupt.check() {
                    self.abandoned.store(true, Ordering::Relaxed);
                    return Err(e);
                }
            }
            std::thread::sleep(WAIT_STEP);
        }
    }

    /// Waits (polling `interrupt`) for work an interrupt abandoned, if any: a submission still on
    /// the worker thread, or one the GPU is still running.
    pub fn finish_pending(&self, interrupt: &Interrupt) -> Result<()> {
        let rx = self.pending.lock().unwrap_or_else(|p| p.into_inner()).take();
        if let Some(rx) = rx {
            self.await_worker(rx, interrupt)?;
        }
        if self.abandoned.load(Ordering::Relaxed) {
            self.wait_interruptible(interrupt)?;
        }
        Ok(())
    }

    fn await_worker(&self, rx: mpsc::Receiver<Result<()>>, interrupt: &Interrupt) -> Result<()> {
        loop {
            match rx.recv_timeout(Interrupt::POLL) {
                Ok(done) => return done,
                Err(mpsc::RecvTimeoutError::Timeout) => {
                    if let Err(e) = interrupt.check() {
                        *self.pending.lock().unwrap_or_else(|p| p.into_inner()) = Some(rx);
                        return Err(e);
                    }
                }
                Err(mpsc::RecvTimeoutError::Disconnected) => {
                    return Err(Error::Device("the thread submitting GPU work stopped unexpectedly".into()))
                }
            }
        }
    }

    pub fn adapter_description(&self) -> String {
        format!(
            "{} ({:?}, {:?}, driver {} {})",
            self.info.name, self.info.backend, self.info.device_type, self.info.driver, self.info.driver_info
        )
    }
}

impl GpuContext {
    /// Records the read-back of a Depth32Float texture (usages `COPY_SRC | TEXTURE_BINDING`): a
    /// copy where the backend can copy depth into buffers, else through a shader
    /// (`gpu::depth_read`; GL).
    pub fn read_depth(&self, enc: &mut wgpu::CommandEncoder, tex: &wgpu::Texture) -> DepthReadback {
        let (w, h) = (tex.width(), tex.height());
        if self.depth_copies {
            DepthReadback::Copy(ReadbackTexture::new(&self.device, enc, tex, w, h, 4, wgpu::TextureAspect::DepthOnly))
        } else {
            let view = tex.create_view(&Default::default());
            self.depth_reader.record(&self.device, enc, &view, (w, h), self.limits.max_storage_buffer_binding_size)
        }
    }

    /// Checks an image size against this device's texture limit.
    pub fn check_image_size(&self, width: u32, height: u32) -> Result<()> {
        check_size(width, height, self.limits.max_texture_dimension_2d)
    }
}

/// Checks an image size against a device limit `max`.
pub fn check_size(width: u32, height: u32, max: u32) -> Result<()> {
    use crate::error::ensure;
    ensure(width >= 1, "width", || format!("width is {width}; expected 1..={max}"))?;
    ensure(height >= 1, "height", || format!("height is {height}; expected 1..={max}"))?;
    ensure(width <= max, "width", || format!("width is {width}; this device's max texture size is {max}"))?;
    ensure(height <= max, "height", || format!("height is {height}; this device's max texture size is {max}"))?;
    Ok(())
}
