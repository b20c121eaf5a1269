//! The editor's one renderer, on a thread of its own: the rendered preview of the page's view,
//! and the final render of the scene's camera.
//!
//! The preview restarts whenever the scene or the view changes (a new *generation*), first at a
//! quarter of the preview size with direct light only (no photons: the edit shows within a
//! fraction of a second), then at half size with an eighth of the photons and no final
//! gathering, then at the full preview size with the scene's photon settings, pass after pass
//! (progressive photon mapping, docs/progressive.md) until `MAX_PREVIEW_PASSES`. A change during
//! a step stops it within `PREVIEW_STOP_PATHS` paths (photon tracing included: the renderer's
//! stop flag, looked at between small submissions) and the new generation starts at once.
//!
//! The thread drives one `render::Renderer` (the renderer the command line and the Python
//! package drive), made at the first step and kept as long as the thread: a change re-prepares
//! the scene and `Renderer::update_scene` writes only the arrays that changed on a device (an
//! edit of a material writes the material array), in place where their sizes allow; passes of
//! one scene, view and size reuse the prepared scene and upload nothing. The final render runs
//! on the same thread and renderer, with the scene as it was when it started; it goes on when
//! every page is closed, and the preview waits for it.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Condvar, Mutex};
use std::time::{Duration, Instant};

use glam::Vec3;
use serde::Deserialize;
use serde_json::json;
use tokio::sync::broadcast;

use crate::gpu::{GpuContext, GpuOptions};
use crate::io::Image;
use crate::render::progressive::{Accumulator, Budget};
use crate::render::{
    prepare, set_thread_stop_flag, set_thread_stop_paths, FrameSettings, PhotonSettings, RenderOutput,
};
use crate::scene::{Projection, Scene};

/// Passes of the full-size preview before it stops refining.
pub const MAX_PREVIEW_PASSES: u32 = 64;
/// Paths (photon or camera) between two looks at the stop flag in a preview step: on lavapipe
/// with two busy cores 4096 camera paths of cornell-box take about 80 ms (16k: 300 ms), so a
/// stale step ends within the half second an edit may take to show, and the passes' rate did
/// not measurably drop (BENCHMARKS.md); a real GPU pays a few microseconds per submission.
const PREVIEW_STOP_PATHS: u64 = 1 << 12;
/// Largest final render the editor accepts, in pixels (the scene's resolution).
const MAX_FINAL_PIXELS: u64 = 4096 * 4096;

/// The page's viewport camera, which the preview renders from.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct View {
    pub position: [f32; 3],
    pub look_at: [f32; 3],
    pub up: [f32; 3],
    /// Vertical field of view, degrees.
    pub fov: f32,
    /// The viewport's size in CSS pixels; the preview keeps its aspect ratio.
    pub width: u32,
    pub height: u32,
}

impl View {
    fn check(&self) -> Result<(), String> {
        let finite = self.position.iter().chain(&self.look_at).chain(&self.up).all(|v| v.is_finite());
        if !finite || !(0.01..179.0).contains(&self.fov) {
            return Err("the view needs finite vectors and a field of view in (0, 179) degrees".into());
        }
        if self.width == 0 || self.height == 0 || self.width > 16384 || self.height > 16384 {
            return Err("the view's size must be 1 to 16384 pixels a side".into());
        }
        // The tests of `Camera::basis`, one at a time, so the message blames the right vector.
        let (position, look_at, up) = (Vec3::from(self.position), Vec3::from(self.look_at), Vec3::from(self.up));
        let Some(forward) = (look_at - position).try_normalize() else {
            return Err(
                "the view's position equals its target (look_at), so it has no direction of view; move one of them"
                    .into(),
            );
        };
        match up.try_normalize() {
            None => return Err("the view's up direction is zero; give one roughly perpendicular to the view".into()),
            Some(u) if forward.cross(u).length() <= 1e-6 => {
                return Err("the view's up direction is parallel to its direction of view".into())
            }
            Some(_) => {}
        }
        Ok(())
    }
}

/// Which backend the renderer thread uses.
#[derive(Clone, Debug)]
pub enum BackendChoice {
    /// The Vulkan kernels; with `fallback`, the CPU backend when the device will not open.
    Gpu {
        options: GpuOptions,
        fallback: bool,
    },
    Cpu,
}

/// A final render's limits: the first reached wins.
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FinalRequest {
    /// Passes to render; default the scene's `[render] passes` (or the most there are with a time).
    pub passes: Option<u32>,
    /// Seconds of wall time.
    pub seconds: Option<f64>,
}

/// What the renderer tells the pages.
#[derive(Clone, Debug)]
pub enum Event {
    /// A preview or final-render image: a JSON header and the PNG bytes.
    Frame { header: serde_json::Value, png: Arc<Vec<u8>> },
    /// A JSON message (final render status, preview errors).
    Message(serde_json::Value),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Mode {
    Preview,
    Final,
}

struct State {
    scene: Option<Arc<Scene>>,
    view: Option<View>,
    /// Whose view it is (the server's page session; 0: anyone's), named in each frame's
    /// header so a page shows only the frames of its own view.
    owner: u64,
    /// Bumped by every change of the scene or the view.
    generation: u64,
    /// When the current generation began, for the edit-to-frame latency.
    changed_at: Instant,
    /// When the edit that made the current scene reached the server (`set_scene_of_edit`),
    /// before it was applied and parsed: the frame's `since_edit_ms`.
    edit_at: Option<Instant>,
    mode: Mode,
    final_request: Option<(FinalRequest, Arc<Scene>)>,
    cancel_final: bool,
    final_status: serde_json::Value,
    final_image: Option<Arc<Image>>,
    shutdown: bool,
    /// Longest side of the full-size preview, pixels.
    preview_size: u32,
    /// Denoise the preview frames (the page's toggle; on by default where the library loads).
    denoise: bool,
}

struct Shared {
    state: Mutex<State>,
    /// Stops the renderer thread's render after the dispatch under way (its own flag, so one
    /// server never stops another's renders, nor `photonix render`'s).
    stop: Arc<AtomicBool>,
    wake: Condvar,
    events: broadcast::Sender<Event>,
    /// The newest preview frame, for a page that connects after it was sent: a converged
    /// preview sends no more, and the page would stay blank.
    last_preview: Mutex<Option<Event>>,
}

/// The handle the server holds; dropping it stops the thread.
pub struct Renderer {
    shared: Arc<Shared>,
    thread: Option<std::thread::JoinHandle<()>>,
    /// "cpu" or the Vulkan device's name.
    pub device: String,
    /// Why the preview cannot be denoised (Open Image Denoise missing), or `None`.
    pub denoiser: Option<String>,
}

impl Renderer {
    /// Starts the renderer thread on `backend`; fails when the GPU backend was asked for and no
    /// device opens.
    pub fn start(backend: BackendChoice, preview_size: u32) -> Result<Renderer, String> {
        let (events, _) = broadcast::channel(64);
        let shared = Arc::new(Shared {
            state: Mutex::new(State {
                scene: None,
                view: None,
                owner: 0,
                generation: 0,
                changed_at: Instant::now(),
                edit_at: None,
                mode: Mode::Preview,
                final_request: None,
                cancel_final: false,
                final_status: json!({ "type": "render", "state": "idle" }),
                final_image: None,
                shutdown: false,
                preview_size: preview_size.clamp(16, 4096),
                denoise: crate::gpu::oidn::available().is_ok(),
            }),
            wake: Condvar::new(),
            stop: Arc::new(AtomicBool::new(false)),
            events,
            last_preview: Mutex::new(None),
        });
        let (ready_tx, ready_rx) = std::sync::mpsc::channel();
        let thread_shared = shared.clone();
        let thread = std::thread::Builder::new()
            .name("photonix-renderer".into())
            .spawn(move || run(thread_shared, backend, ready_tx))
            .map_err(|e| format!("cannot start the renderer thread: {e}"))?;
        let device = ready_rx.recv().map_err(|_| "the renderer thread stopped while starting".to_string())??;
        let denoiser = crate::gpu::oidn::available().err().map(|e| e.to_string());
        Ok(Renderer { shared, thread: Some(thread), device, denoiser })
    }

    /// Turns the preview's denoising on or off; a new generation shows it at once. Refused
    /// where the library is missing (the message says what to install).
    pub fn set_denoise(&self, on: bool) -> Result<(), String> {
        if let (true, Some(missing)) = (on, &self.denoiser) {
            return Err(missing.clone());
        }
        self.change(|s| s.denoise = on);
        Ok(())
    }

    /// Whether the preview is denoised now.
    pub fn denoise(&self) -> bool {
        self.shared.state.lock().expect("renderer state lock").denoise
    }

    pub fn subscribe(&self) -> broadcast::Receiver<Event> {
        self.shared.events.subscribe()
    }

    /// The newest preview frame sent, if any.
    pub fn last_preview(&self) -> Option<Event> {
        self.shared.last_preview.lock().expect("last preview lock").clone()
    }

    /// Starts a new preview generation with `scene`.
    pub fn set_scene(&self, scene: Arc<Scene>) {
        self.change(|s| {
            s.scene = Some(scene);
            s.edit_at = None;
        });
    }

    /// `set_scene` for the edit that reached the server at `edit_at`: the frames say how long
    /// after it they came (`since_edit_ms`: the edit applied, parsed, the scene sent and
    /// rendered).
    pub fn set_scene_of_edit(&self, scene: Arc<Scene>, edit_at: Instant) {
        self.change(|s| {
            s.scene = Some(scene);
            s.edit_at = Some(edit_at);
        });
    }

    /// Starts a new preview generation from `view`, for the page `owner`; the same view of the
    /// same page again changes nothing (the preview goes on refining).
    pub fn set_view(&self, view: View, owner: u64) -> Result<(), String> {
        view.check()?;
        {
            let s = self.shared.state.lock().expect("renderer state lock");
            if s.view == Some(view) && s.owner == owner {
                return Ok(());
            }
        }
        self.change(|s| {
            s.view = Some(view);
            s.owner = owner;
        });
        Ok(())
    }

    fn change(&self, apply: impl FnOnce(&mut State)) {
        let mut s = self.shared.state.lock().expect("renderer state lock");
        apply(&mut s);
        s.generation += 1;
        s.changed_at = Instant::now();
        // Stop the preview pass under way; the thread clears the flag before reading the
        // generation, so a change is never lost between the two. A final render is not stopped.
        if s.mode == Mode::Preview {
            self.shared.stop.store(true, Ordering::SeqCst);
        }
        self.shared.wake.notify_all();
    }

    /// Queues a final render of `scene` (its own camera and settings).
    pub fn start_final(&self, request: FinalRequest, scene: Arc<Scene>) -> Result<(), String> {
        if let Some(s) = request.seconds {
            // Say which bound is broken: 1e300 s is positive, just beyond the longest budget.
            if !(s.is_finite() && s > 0.0) {
                return Err(format!(
                    "the time budget is {} s; give a positive number of seconds, at most {} (365 days)",
                    crate::limits::fmt_number(s),
                    crate::limits::MAX_DURATION_SECONDS
                ));
            }
            if s > crate::limits::MAX_DURATION_SECONDS {
                return Err(format!(
                    "the time budget is {} s, more than the longest, {} s (365 days); give a shorter one",
                    crate::limits::fmt_number(s),
                    crate::limits::MAX_DURATION_SECONDS
                ));
            }
        }
        if request.passes.is_some_and(|p| p == 0 || p > crate::limits::MAX_PASSES) {
            return Err(format!("passes must be 1 to {}", crate::limits::MAX_PASSES));
        }
        let pixels = scene.camera.width as u64 * scene.camera.height as u64;
        if pixels > MAX_FINAL_PIXELS {
            return Err(format!(
                "the editor renders at most {MAX_FINAL_PIXELS} pixels; use `photonix render` for this one"
            ));
        }
        let mut s = self.shared.state.lock().expect("renderer state lock");
        if s.mode == Mode::Final || s.final_request.is_some() {
            return Err("a final render is running; cancel it first".into());
        }
        s.final_request = Some((request, scene));
        s.cancel_final = false;
        s.final_image = None;
        s.final_status = json!({ "type": "render", "state": "queued" });
        self.shared.stop.store(true, Ordering::SeqCst);
        self.shared.wake.notify_all();
        Ok(())
    }

    /// Asks the final render to stop after the dispatch under way; the passes done are kept.
    pub fn cancel_final(&self) -> bool {
        let mut s = self.shared.state.lock().expect("renderer state lock");
        if s.mode != Mode::Final && s.final_request.is_none() {
            return false;
        }
        s.cancel_final = true;
        self.shared.stop.store(true, Ordering::SeqCst);
        true
    }

    pub fn final_status(&self) -> serde_json::Value {
        self.shared.state.lock().expect("renderer state lock").final_status.clone()
    }

    /// The last final render's image (the mean of its passes).
    pub fn final_image(&self) -> Option<Arc<Image>> {
        self.shared.state.lock().expect("renderer state lock").final_image.clone()
    }
}

impl Drop for Renderer {
    fn drop(&mut self) {
        {
            let mut s = self.shared.state.lock().expect("renderer state lock");
            s.shutdown = true;
            s.cancel_final = true;
        }
        self.shared.stop.store(true, Ordering::SeqCst);
        self.shared.wake.notify_all();
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

/// What a step cost besides its render: preparing the scene (BVH and arrays) and writing it to
/// the device. A step that renders the scene, view and size of the step before reuses both.
#[derive(Debug, Default)]
struct StepCost {
    prepare_ms: f64,
    upload_ms: f64,
    /// The scene arrays written to the device (GPU backend): only those that changed.
    written: Vec<&'static str>,
    /// The render's own stages (photons, render, download), ms.
    stages: serde_json::Map<String, serde_json::Value>,
}

/// The scene the backend prepared last, kept while the scene, the view and the size stay (the
/// `Arc` held here keeps its address from being reused by another scene).
struct Prepared {
    scene: Arc<Scene>,
    view: Option<View>,
    settings: FrameSettings,
    buffers: crate::render::SceneBuffers,
}

/// The editor's backend: one `render::Renderer` kept across frames (the CPU twin, or the
/// kernels and buffers on a device), with the scene prepared last.
struct Backend<'a> {
    ctx: Option<&'a GpuContext>,
    renderer: Option<crate::render::Renderer<'a>>,
    prepared: Option<Prepared>,
    /// The photon settings the renderer holds.
    renderer_photons: Option<PhotonSettings>,
}

impl Backend<'_> {
    /// Renders pass `pass` of `scene`, seen from `view` when given (else its own camera), at the
    /// size of `settings`.
    #[allow(clippy::too_many_arguments)]
    fn render(
        &mut self,
        scene: &Arc<Scene>,
        view: Option<&View>,
        settings: &FrameSettings,
        photons: Option<&PhotonSettings>,
        spp: u32,
        pass: u32,
        features: bool,
    ) -> Result<(RenderOutput, StepCost), String> {
        let mut cost = StepCost::default();
        let same = self.prepared.as_ref().is_some_and(|p| {
            let (a, b) = (&p.settings, settings);
            let same_settings = (a.width, a.height, a.max_depth, a.seed) == (b.width, b.height, b.max_depth, b.seed);
            Arc::ptr_eq(&p.scene, scene) && p.view.as_ref() == view && same_settings
        });
        // Only the size changed (the next step of the same scene and view: quarter, half, full
        // size): the prepared scene serves as it is but for the frame's size and the film's
        // width, which `prepare` derives from them alone. Preparing again (the BVH over every
        // triangle: 240-360 ms for a 100k-triangle mesh here) made an edit wait for the stale
        // step's prepare, which no stop flag interrupts.
        let resized = !same
            && self.prepared.as_ref().is_some_and(|p| {
                let (a, b) = (&p.settings, settings);
                Arc::ptr_eq(&p.scene, scene)
                    && p.view.as_ref() == view
                    && (a.max_depth, a.seed) == (b.max_depth, b.seed)
            });
        if resized {
            let p = self.prepared.as_mut().expect("checked above");
            let frame = &mut p.buffers.frame;
            if frame.camera_kind != crate::layout::constants::CAMERA_LATLONG {
                // camera_right = right * tan(fov / 2) * aspect: scale by the aspects' ratio.
                let old_aspect = frame.width as f32 / frame.height.max(1) as f32;
                let new_aspect = settings.width as f32 / settings.height.max(1) as f32;
                frame.camera_right = (Vec3::from(frame.camera_right) * (new_aspect / old_aspect)).into();
            }
            frame.width = settings.width;
            frame.height = settings.height;
            p.settings = *settings;
        } else if !same {
            let t = Instant::now();
            let viewed;
            let target: &Scene = match view {
                Some(v) => {
                    viewed = view_scene(scene, v, settings.width, settings.height);
                    if viewed.camera.basis().is_none() {
                        return Err("the view's up direction is parallel to its direction of view".into());
                    }
                    &viewed
                }
                None => scene,
            };
            let buffers = prepare(target, settings).map_err(|e| e.to_string())?;
            self.prepared = Some(Prepared { scene: scene.clone(), view: view.copied(), settings: *settings, buffers });
            cost.prepare_ms = t.elapsed().as_secs_f64() * 1e3;
        }
        let buffers = &self.prepared.as_ref().expect("prepared just above").buffers;
        if let Some(p) = photons {
            crate::render::photons::check_radii(buffers, p).map_err(|e| e.to_string())?;
        }
        let err = |e: crate::gpu::GpuError| e.to_string();
        let t = Instant::now();
        match &mut self.renderer {
            Some(r) => {
                if !same || self.renderer_photons.as_ref() != photons {
                    if let Err(e) = r.update_scene(buffers, photons) {
                        // The renderer does not hold this scene: the next step must upload it.
                        self.prepared = None;
                        return Err(err(e));
                    }
                    cost.written = r.last_written().to_vec();
                }
            }
            None => {
                // Made with the scene's photon settings, so that on a device the photon kernels
                // are created now and not in the first step that traces photons.
                let mut r =
                    crate::render::Renderer::new(self.ctx, buffers, photons.or(scene.photons.as_ref())).map_err(err)?;
                if photons.is_none() {
                    r.update_scene(buffers, None).map_err(err)?;
                }
                self.renderer = Some(r);
                cost.written = vec!["all"];
            }
        }
        self.renderer_photons = photons.copied();
        if self.ctx.is_some() {
            cost.upload_ms = t.elapsed().as_secs_f64() * 1e3;
        }
        let r = self.renderer.as_mut().expect("made just above");
        r.set_features(features);
        let out = r.render_pass(spp, pass, &mut |_, _| {}).map_err(err)?;
        Ok((out, cost))
    }
}

fn run(shared: Arc<Shared>, backend: BackendChoice, ready: std::sync::mpsc::Sender<Result<String, String>>) {
    let ctx = match &backend {
        BackendChoice::Cpu => None,
        BackendChoice::Gpu { options, fallback } => match GpuContext::new(options) {
            Ok(ctx) => Some(ctx),
            Err(e) if *fallback => {
                eprintln!("warning: {e}; the editor renders on the CPU backend instead");
                None
            }
            Err(e) => {
                let _ = ready.send(Err(e.to_string()));
                return;
            }
        },
    };
    let device = match &ctx {
        Some(ctx) => format!("gpu: {}", ctx.info().name),
        None => format!("cpu ({} threads)", rayon::current_num_threads()),
    };
    set_thread_stop_flag(Some(shared.stop.clone()));
    // PHOTONIX_PREVIEW_STOP_PATHS overrides the step's stop granularity (0: the backends' own
    // submissions), to weigh latency against throughput on a given device.
    let stop_paths = match std::env::var("PHOTONIX_PREVIEW_STOP_PATHS").ok().and_then(|v| v.parse::<u64>().ok()) {
        Some(0) => None,
        Some(paths) => Some(paths),
        None => Some(PREVIEW_STOP_PATHS),
    };
    set_thread_stop_paths(stop_paths);
    let _ = ready.send(Ok(device.clone()));
    let mut backend = Backend { ctx: ctx.as_ref(), renderer: None, prepared: None, renderer_photons: None };
    // Open Image Denoise's device, opened at the first denoised step and kept: CUDA where the
    // kernels run on an NVIDIA GPU, else the CPU (src/render/denoise.rs).
    let cuda = ctx.as_ref().is_some_and(|c| crate::render::denoise::prefers_cuda(&c.info().name));
    let mut denoiser: Option<crate::gpu::oidn::Denoiser> = None;
    let mut preview = PreviewState::default();
    // What the last stopped step did before it stopped, reported with the next frame (where an
    // edit's wait for the stale step went).
    let mut stale: Option<serde_json::Value> = None;
    loop {
        // Wait for work: a final render, or a preview step still to do.
        let mut s = shared.state.lock().expect("renderer state lock");
        loop {
            if s.shutdown {
                return;
            }
            if s.final_request.is_some() {
                break;
            }
            if s.scene.is_some() && s.view.is_some() && (preview.generation != s.generation || !preview.finished()) {
                break;
            }
            s = shared.wake.wait(s).expect("renderer state lock");
        }
        if let Some((request, scene)) = s.final_request.take() {
            s.mode = Mode::Final;
            shared.stop.store(false, Ordering::SeqCst);
            drop(s);
            // The final render's submissions are the backends' own (fewer, larger); a cancel
            // waits for the one under way.
            set_thread_stop_paths(None);
            final_render(&shared, &mut backend, &request, &scene);
            set_thread_stop_paths(stop_paths);
            let mut s = shared.state.lock().expect("renderer state lock");
            s.mode = Mode::Preview;
            // The preview starts again from its first step.
            s.generation += 1;
            s.changed_at = Instant::now();
            continue;
        }
        // Clear the stop flag, then read the generation (see `Renderer::change`).
        shared.stop.store(false, Ordering::SeqCst);
        let generation = s.generation;
        let changed_at = s.changed_at;
        let edit_at = s.edit_at;
        let scene = s.scene.clone().expect("checked above");
        let view = s.view.expect("checked above");
        let owner = s.owner;
        let preview_size = s.preview_size;
        let denoise = s.denoise;
        drop(s);
        if denoise && denoiser.is_none() {
            match crate::gpu::oidn::Denoiser::open(cuda) {
                Ok(mut d) => {
                    // A change cancels a running denoise too: the next frame need not wait for it.
                    d.set_stop_flag(Some(shared.stop.clone()));
                    denoiser = Some(d);
                }
                Err(e) => {
                    // Raw frames from now on; the page hears why.
                    shared.state.lock().expect("renderer state lock").denoise = false;
                    let message = format!("preview: not denoised: {e}");
                    let _ = shared.events.send(Event::Message(json!({ "type": "error", "message": message })));
                }
            }
        }
        let step_denoiser = if denoise { denoiser.as_mut() } else { None };
        if preview.generation != generation {
            preview = PreviewState { generation, ..Default::default() };
        }
        let step = preview.step;
        let t = Instant::now();
        let result = preview_step(&mut backend, &scene, &view, preview_size, &mut preview, step_denoiser);
        let current = shared.state.lock().expect("renderer state lock").generation == generation;
        match result {
            Ok((Some(image), cost)) if current => {
                preview.step += 1;
                let png = encode_png(&image, 0.0);
                let header = json!({
                    "type": "frame",
                    "kind": "preview",
                    "owner": owner,
                    "generation": generation,
                    "step": step,
                    "passes": preview.accumulator.as_ref().map_or(0, |a| a.passes),
                    "width": image.width,
                    "height": image.height,
                    "render_ms": t.elapsed().as_secs_f64() * 1e3,
                    "prepare_ms": cost.prepare_ms,
                    "upload_ms": cost.upload_ms,
                    "uploaded": cost.written,
                    "stages": cost.stages,
                    "stale": stale.take(),
                    "since_change_ms": changed_at.elapsed().as_secs_f64() * 1e3,
                    "since_edit_ms": edit_at.map(|t| t.elapsed().as_secs_f64() * 1e3),
                    "device": device,
                    "denoised": denoise && denoiser.is_some(),
                });
                let frame = Event::Frame { header, png: Arc::new(png) };
                *shared.last_preview.lock().expect("last preview lock") = Some(frame.clone());
                let _ = shared.events.send(frame);
            }
            // Stopped by a change, or a change came during the step: start the new generation.
            Ok((_, cost)) => {
                stale = Some(json!({ "step": step, "ms": t.elapsed().as_secs_f64() * 1e3, "stages": cost.stages }));
            }
            Err(message) => {
                preview.failed = true;
                let _ = shared
                    .events
                    .send(Event::Message(json!({ "type": "error", "message": format!("preview: {message}") })));
            }
        }
    }
}

#[derive(Default)]
struct PreviewState {
    generation: u64,
    /// 0: quarter size, 1: half size, 2..: progressive passes at full size.
    step: u32,
    accumulator: Option<Accumulator>,
    failed: bool,
}

impl PreviewState {
    fn finished(&self) -> bool {
        self.failed || self.step >= 2 + MAX_PREVIEW_PASSES
    }
}

/// The scene seen from the view at `width` x `height`, as a pinhole camera.
fn view_scene(scene: &Scene, view: &View, width: u32, height: u32) -> Scene {
    let mut s = scene.clone();
    let c = &mut s.camera;
    c.position = Vec3::from(view.position);
    c.look_at = Vec3::from(view.look_at);
    c.up = Vec3::from(view.up);
    c.fov_deg = view.fov;
    c.projection = Projection::Perspective;
    c.lens = None;
    c.width = width;
    c.height = height;
    s
}

/// Preview size for a step: the view's aspect, the long side `preview_size` (never more than
/// the view's own pixels), halved per level below full.
fn preview_resolution(view: &View, preview_size: u32, level_divisor: u32) -> (u32, u32) {
    let long = view.width.max(view.height).min(preview_size).max(8) / level_divisor;
    let long = long.max(8) as f32;
    let aspect = view.width as f32 / view.height as f32;
    let (w, h) = if aspect >= 1.0 { (long, long / aspect) } else { (long * aspect, long) };
    ((w.round() as u32).max(1), (h.round() as u32).max(1))
}

/// Renders one preview step; no image when a change stopped it.
/// Renders one preview step, denoised with `denoiser` where given (its time in the cost's
/// stages as `denoise`); no image when a change stopped it.
fn preview_step(
    backend: &mut Backend,
    scene: &Arc<Scene>,
    view: &View,
    preview_size: u32,
    preview: &mut PreviewState,
    denoiser: Option<&mut crate::gpu::oidn::Denoiser>,
) -> Result<(Option<Image>, StepCost), String> {
    let step = preview.step;
    let (divisor, photons, pass) = match step {
        // A quick look: a sixteenth of the pixels and direct light only (no photon tracing, so
        // an edit shows at once even on lavapipe); then a quarter of the pixels with an eighth
        // of the photons, the global map read directly (no final gathering).
        0 => (4, None, 0),
        1 => (2, scene.photons.map(|p| scaled(p, 8, 0)), 0),
        _ => (1, scene.photons, step - 2),
    };
    let (width, height) = preview_resolution(view, preview_size, divisor);
    let settings = FrameSettings { width, height, max_depth: scene.render.max_depth, seed: scene.render.seed };
    let denoise = denoiser.is_some();
    let (out, mut cost) = backend.render(scene, Some(view), &settings, photons.as_ref(), 1, pass, denoise)?;
    for (name, time) in &out.stats.stages {
        cost.stages.insert(name.clone(), json!(time.as_secs_f64() * 1e3));
    }
    if !out.complete {
        return Ok((None, cost));
    }
    let (image, features) = if step < 2 {
        (out.image, out.features)
    } else {
        let acc = preview.accumulator.get_or_insert_with(|| Accumulator::new(width, height));
        acc.add(pass, &out);
        (acc.mean().combined(), acc.mean_features())
    };
    let Some(denoiser) = denoiser else { return Ok((Some(image), cost)) };
    let t = Instant::now();
    let denoised = match crate::render::denoise::denoise_image(denoiser, &image, features.as_ref()) {
        Ok(image) => image,
        // A change stopped it: like a stopped render, no frame.
        Err(crate::gpu::oidn::DenoiseError::Cancelled) => return Ok((None, cost)),
        Err(e) => return Err(e.to_string()),
    };
    cost.stages.insert("denoise".into(), json!(t.elapsed().as_secs_f64() * 1e3));
    Ok((Some(denoised), cost))
}

/// Photon settings with `1/divisor` of the paths (at least 1000) and `gather_rays` final
/// gathering rays.
fn scaled(p: PhotonSettings, divisor: u32, gather_rays: u32) -> PhotonSettings {
    PhotonSettings {
        photons: (p.photons / divisor).max(1000.min(p.photons)),
        caustic_photons: (p.caustic_photons / divisor).max(1000.min(p.caustic_photons)),
        gather_rays,
        ..p
    }
}

/// Runs a final render, publishing its status after every pass.
fn final_render(shared: &Shared, backend: &mut Backend, request: &FinalRequest, scene: &Arc<Scene>) {
    let start = Instant::now();
    let passes = request.passes.unwrap_or(if request.seconds.is_some() {
        crate::limits::MAX_PASSES
    } else {
        scene.render.passes
    });
    let budget = Budget {
        first: 0,
        end: passes,
        time: request.seconds.map(Duration::from_secs_f64),
        target_error: None,
        adaptive: false,
    };
    let settings = FrameSettings {
        width: scene.camera.width,
        height: scene.camera.height,
        max_depth: scene.render.max_depth,
        seed: scene.render.seed,
    };
    let status = |state: &str, acc: Option<&Accumulator>, message: Option<&str>| {
        let elapsed = start.elapsed().as_secs_f64();
        let done = acc.map_or(0, |a| a.passes);
        // Remaining: the passes left at the mean pass time, or the time budget left, whichever
        // ends the render first.
        let by_passes = (done > 0).then(|| elapsed / done as f64 * (passes - done) as f64);
        let by_time = request.seconds.map(|t| (t - elapsed).max(0.0));
        let remaining = match (by_passes, by_time) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        };
        json!({
            "type": "render",
            "state": state,
            "passes": done,
            "total_passes": passes,
            "seconds": request.seconds,
            "elapsed": elapsed,
            "remaining": if state == "running" { remaining } else { Some(0.0) },
            "error_estimate": acc.and_then(|a| a.error_estimate()),
            "width": settings.width,
            "height": settings.height,
            "message": message,
        })
    };
    let publish = |value: serde_json::Value, image: Option<Image>| {
        let mut s = shared.state.lock().expect("renderer state lock");
        s.final_status = value.clone();
        if let Some(image) = image {
            let png = encode_png(&image, 0.0);
            s.final_image = Some(Arc::new(image));
            let mut header = value.clone();
            header["type"] = json!("frame");
            header["kind"] = json!("final");
            let _ = shared.events.send(Event::Frame { header, png: Arc::new(png) });
        }
        drop(s);
        let _ = shared.events.send(Event::Message(value));
    };
    publish(status("running", None, None), None);
    let result = crate::render::progressive::render_progressive(
        settings.width,
        settings.height,
        &budget,
        // One pass per output: the editor shows each as it lands.
        1,
        |pass, _, _| {
            backend
                .render(scene, None, &settings, scene.photons.as_ref(), scene.render.spp, pass, false)
                .map(|(out, _)| out)
        },
        |acc, _| {
            publish(status("running", Some(acc), None), Some(acc.mean().combined()));
            Ok(())
        },
    );
    let cancelled = shared.state.lock().expect("renderer state lock").cancel_final;
    match result {
        Ok((acc, _)) => {
            let state = if cancelled { "cancelled" } else { "done" };
            let image = (acc.passes > 0).then(|| acc.mean().combined());
            publish(status(state, Some(&acc), None), image);
        }
        Err(message) => publish(status("failed", None, Some(&message)), None),
    }
}

/// 8-bit sRGB PNG bytes of `image`.
pub fn encode_png(image: &Image, exposure: f32) -> Vec<u8> {
    use ::image::ImageEncoder;
    let mut out = Vec::new();
    let pixels = crate::io::image::to_srgb8(image, exposure);
    // Fast compression: preview frames are small and sent many times a second.
    let encoder = ::image::codecs::png::PngEncoder::new_with_quality(
        &mut out,
        ::image::codecs::png::CompressionType::Fast,
        ::image::codecs::png::FilterType::Sub,
    );
    encoder
        .write_image(&pixels, image.width, image.height, ::image::ExtendedColorType::Rgb8)
        .expect("an in-memory PNG of matching size always encodes");
    out
}

/// Linear-radiance OpenEXR bytes of `image`.
pub fn encode_exr(image: &Image) -> Result<Vec<u8>, String> {
    use exr::prelude::*;
    let w = image.width as usize;
    let channels = SpecificChannels::rgb(|pos: Vec2<usize>| {
        let p = image.pixels[pos.y() * w + pos.x()];
        (p[0], p[1], p[2])
    });
    let encoding = Encoding { line_order: LineOrder::Increasing, ..Encoding::FAST_LOSSLESS };
    let mut out = std::io::Cursor::new(Vec::new());
    exr::image::Image::from_encoded_channels((w, image.height as usize), encoding, channels)
        .write()
        .to_buffered(&mut out)
        .map_err(|e| e.to_string())?;
    Ok(out.into_inner())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn view(position: [f32; 3], look_at: [f32; 3], up: [f32; 3]) -> View {
        View { position, look_at, up, fov: 45.0, width: 64, height: 48 }
    }

    #[test]
    fn a_bad_view_blames_the_vector_at_fault() {
        // Position on the target: the up direction is not to blame.
        let e = view([1.0, 2.0, 3.0], [1.0, 2.0, 3.0], [0.0, 1.0, 0.0]).check().unwrap_err();
        assert!(e.contains("position equals its target") && !e.contains("up direction"), "{e}");
        let e = view([0.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 0.0, 0.0]).check().unwrap_err();
        assert!(e.contains("up direction is zero"), "{e}");
        let e = view([0.0, 0.0, 0.0], [0.0, 5.0, 0.0], [0.0, 2.0, 0.0]).check().unwrap_err();
        assert!(e.contains("parallel to its direction of view"), "{e}");
        assert!(view([0.0, 1.0, 4.0], [0.0, 0.5, 0.0], [0.0, 1.0, 0.0]).check().is_ok());
    }
}
