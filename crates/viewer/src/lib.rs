//! The interactive viewer: a window showing the progressive image, refined frame by frame
//! as the thesis's running mean, with a mouse and keyboard camera.
//!
//! [`run`] opens a window (winit) the size of the image; a render thread (the private
//! `worker` module) asks the given [`PreparedScene`] (prepared by any backend) for
//! `spp_per_frame` more samples of every pixel each frame, through the backend's
//! [`tracer::Accumulation`] (the GPU keeps its statistics on the device), and hands the
//! per-pixel running mean g_i = g_{i−1} + (f_i − g_{i−1})/i to the window. The window
//! never waits for a frame: input is handled while one renders. Any
//! camera move starts the accumulation again, with one quarter-size preview frame first
//! (shown scaled up, so dragging stays fluid); a resize starts it at the new size.
//!
//! How frames reach the screen: on the GPU backend, through a wgpu surface on the
//! backend's own device — the render thread draws the display kernel's pixels onto the
//! window from the device (`gpu::present`) and nothing is copied to the CPU. (The render
//! thread presents, not the window's: wgpu reconfigures a surface only while no other
//! thread submits work to the device.) Where that surface cannot be made (an adapter that
//! cannot present to the window, or [`ViewerOptions::device_display`] off) and on the
//! CPU backend, the pixels come to the window thread, which shows them through a CPU
//! framebuffer (softbuffer: works under Xvfb and needs no GPU). On the GPU backend the
//! viewer says which on standard error when the window opens.
//!
//! Controls:
//!
//! | input | action |
//! |---|---|
//! | left drag | orbit around the centre (the scene follows the cursor) |
//! | right or middle drag | pan (eye and centre move together) |
//! | wheel, `+` / `-` | dolly towards / away from the centre (never past it) |
//! | `W` `A` `S` `D` | fly forward, left, back, right (eye and centre move together) |
//! | `Q` / `E` | fly down / up |
//! | arrow keys | turn the view from the eye (left, right, up, down) |
//! | Shift | five times larger fly steps and turns |
//! | `R` | back to the starting camera |
//! | `P` / `X` | save the current mean image as `spt-view-<spp>spp.png` (8-bit sRGB) / `.exr` (linear) in the working directory |
//! | Escape, closing the window, Ctrl-C or SIGTERM | quit (writing `--save`'s image) |
//!
//! The title bar shows the samples per pixel so far and the sampling rate:
//! `spt — <title> — <spp> spp, <M> M samples/s (<backend>)`.
//!
//! On Linux the viewer needs an X11 or Wayland display; on a machine without one run it
//! under `xvfb-run`. X11 needs libX11, libX11-xcb, libxcb, libXcursor, libXrandr, libXi
//! and libxkbcommon-x11 at run time (loaded when the window opens); on Debian
//! `apt-get install libx11-6 libx11-xcb1 libxcb1 libxcursor1 libxrandr2 libxi6
//! libxkbcommon0 libxkbcommon-x11-0` (plus `xvfb xauth` for `xvfb-run`).
//!
//! Citations: "the thesis", "the lecture" and the papers named in comments are listed in `docs/references.md`.

pub mod camera_control;
mod worker;

use anyhow::{Context as _, anyhow, bail};
use camera_control::CameraControl;
use std::num::NonZeroU32;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};
use tracer::RenderSettings;
use tracer::film::MAX_PIXEL_SAMPLES;
use tracer::render::{MAX_IMAGE_SIDE, PreparedScene};
use winit::application::ApplicationHandler;
use winit::dpi::{PhysicalPosition, PhysicalSize};
use winit::event::{ElementState, KeyEvent, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{Key, KeyCode, ModifiersState, NamedKey, PhysicalKey};
use winit::window::{Window, WindowId};
use worker::{Command, Frame, Pace, Pixels, Worker};

/// How the viewer window behaves.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ViewerOptions {
    /// Initial image (and window) width in pixels; a resize renders at the new size.
    pub width: u32,
    /// Initial image (and window) height in pixels.
    pub height: u32,
    /// Samples per pixel added every frame (at least 1).
    pub spp_per_frame: u32,
    /// Stop refining once this many samples per pixel have been taken (the window stays
    /// open and a camera move starts again); `None` refines until the film holds
    /// [`MAX_PIXEL_SAMPLES`] (the most its exact sums take: days of frames).
    pub max_spp: Option<u32>,
    /// Quit after this many rendered frames (for tests and CI); also quits once refining
    /// stops at `max_spp`. `None` runs until the window is closed.
    pub exit_after_frames: Option<u32>,
    /// Write the current image here (PNG or EXR by extension) when the viewer quits.
    pub save_on_exit: Option<PathBuf>,
    /// What the title bar calls the scene.
    pub title: String,
    /// On the GPU backend, show frames through a wgpu surface on its device (no copy to
    /// the CPU); `false` reads every frame back to a CPU framebuffer, as other backends do.
    pub device_display: bool,
}

impl Default for ViewerOptions {
    fn default() -> Self {
        Self {
            width: 512,
            height: 512,
            spp_per_frame: 1,
            max_spp: None,
            exit_after_frames: None,
            save_on_exit: None,
            title: "scene".into(),
            device_display: true,
        }
    }
}

impl ViewerOptions {
    /// Rejects an empty or oversized window and zero samples per frame.
    pub fn validate(&self) -> anyhow::Result<()> {
        for (name, v) in [("width", self.width), ("height", self.height)] {
            if v == 0 || v > MAX_IMAGE_SIDE {
                return Err(anyhow!("viewer {name} {v} must be between 1 and {MAX_IMAGE_SIDE}"));
            }
        }
        if self.spp_per_frame == 0 {
            return Err(anyhow!("samples per frame must be at least 1"));
        }
        if self.max_spp == Some(0) {
            return Err(anyhow!("the viewer's maximum samples per pixel must be at least 1"));
        }
        if self.spp_per_frame.max(self.max_spp.unwrap_or(0)) > MAX_PIXEL_SAMPLES {
            return Err(anyhow!("the viewer takes at most {MAX_PIXEL_SAMPLES} samples per pixel"));
        }
        Ok(())
    }
}

/// Figures from a viewer session.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ViewStats {
    /// Frames rendered (render passes), over all camera positions.
    pub frames: u32,
    /// Samples per pixel in the image shown at the end (since the last reset).
    pub spp: u32,
    /// Samples per second over all frames (samples taken / time spent rendering).
    pub samples_per_second: f64,
    /// Full-size frames drawn onto the window from the GPU's device (through the wgpu
    /// surface) rather than read back.
    pub frames_on_device: u32,
    /// Whether the viewer quit on Ctrl-C or SIGTERM.
    pub interrupted: bool,
}

/// Opens a window and shows `scene` refining progressively until the window is closed
/// (or `options.exit_after_frames` frames were rendered).
///
/// The image size is `options`'s (then the window's), not `settings`'s; the camera starts
/// at `scene.camera(settings)` and is then the user's; every other setting (seed,
/// spectral mode, path depth) is used as given. Samples keep their indices across frames
/// (`first_sample` advances), so with a still camera the image after n samples per pixel
/// is the one a single n-spp render gives.
///
/// Fails with "cannot open a window: … (set DISPLAY, or run under xvfb-run)" when there
/// is no display, and with the backend's error if a render pass fails. On Linux it may be
/// called from any thread, once per process (winit allows one event loop per process).
pub fn run(
    scene: Box<dyn PreparedScene>,
    settings: RenderSettings,
    options: ViewerOptions,
) -> anyhow::Result<ViewStats> {
    options.validate()?;
    let mut settings = RenderSettings { width: options.width, height: options.height, ..settings };
    settings.spp = options.spp_per_frame;
    let camera = scene.camera(&settings);
    settings.validate().context("render settings")?;
    camera.validate().map_err(|e| anyhow!("camera: {e}"))?;
    scene.capabilities().check_settings(&settings).context("render settings")?;
    if settings.sampler.needs_sample_budget() && options.max_spp.is_none() {
        bail!(
            "the {} sampler lays its samples out for a known sample count, and the viewer refines without end: \
             give --max-spp, or use --sampler independent",
            settings.sampler.name()
        );
    }
    let scene: Arc<dyn PreparedScene> = Arc::from(scene);
    let first = RenderSettings {
        spp: options.max_spp.unwrap_or(options.spp_per_frame),
        camera: Some(camera),
        ..settings.clone()
    };
    let mut accumulation = Arc::clone(&scene).accumulate(&first).context("render settings")?;
    let on_device = gpu::accumulation::DeviceAccumulation::of(accumulation.as_mut()).is_some();
    let pace = Pace {
        spp_per_frame: options.spp_per_frame,
        max_spp: options.max_spp.unwrap_or(MAX_PIXEL_SAMPLES),
        max_frames: options.exit_after_frames,
        await_window: on_device && options.device_display,
    };
    if on_device && !options.device_display {
        eprintln!("viewer: frames read back to a CPU framebuffer (the wgpu surface was turned off)");
    }
    let bounds = scene.scene().bounds();
    let scene_size = if bounds.is_empty() { 1.0 } else { bounds.extent().length() };

    let mut builder = EventLoop::<Wake>::with_user_event();
    #[cfg(target_os = "linux")]
    winit::platform::x11::EventLoopBuilderExtX11::with_any_thread(&mut builder, true);
    let event_loop = builder.build().map_err(no_window)?;
    let proxy = event_loop.create_proxy();
    let _interrupts = Interrupts::route_to(event_loop.create_proxy());
    let worker = Worker::start(Arc::clone(&scene), accumulation, pace, move || {
        let _ = proxy.send_event(Wake::Frame);
    })?;

    let mut app = App {
        worker,
        generation: 0,
        spp: 0,
        refining: true,
        pixels: vec![0; options.width as usize * options.height as usize],
        control: CameraControl::new(camera, scene_size),
        scene,
        settings,
        options,
        window: None,
        surface: None,
        on_screen: false,
        awaiting_device: pace.await_window,
        interrupted: false,
        input: Input::default(),
        stats: Counters::default(),
        title_at: None,
        title_rate: 0.0,
        error: None,
    };
    event_loop.run_app(&mut app).map_err(|e| anyhow!("the window's event loop failed: {e}"))?;
    if let Some(e) = app.error.take() {
        return Err(e);
    }
    if let Some(path) = app.options.save_on_exit.clone() {
        app.save(&path)?;
    }
    Ok(ViewStats {
        frames: app.stats.frames,
        spp: app.spp,
        samples_per_second: app.stats.rate(),
        frames_on_device: app.stats.frames_on_device,
        interrupted: app.interrupted,
    })
}

/// Where Ctrl-C and SIGTERM go: the running viewer's event loop, which quits as its
/// window's close button makes it (so the image is still saved). The handler is the
/// process's (installed once); with no viewer running the signal ends the process with
/// status 130, as it would have without a handler.
struct Interrupts;

static INTERRUPT_TARGET: std::sync::Mutex<Option<winit::event_loop::EventLoopProxy<Wake>>> =
    std::sync::Mutex::new(None);

impl Interrupts {
    /// Routes interrupts to `proxy` until the returned value is dropped.
    fn route_to(proxy: winit::event_loop::EventLoopProxy<Wake>) -> Self {
        static INSTALLED: std::sync::Once = std::sync::Once::new();
        INSTALLED.call_once(|| {
            let installed = ctrlc::set_handler(|| {
                let target = INTERRUPT_TARGET.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
                // A viewer whose loop has ended is saving and about to return: let it.
                if let Some(proxy) = target.as_ref() {
                    let _ = proxy.send_event(Wake::Quit);
                } else {
                    std::process::exit(130);
                }
            });
            if let Err(e) = installed {
                eprintln!("viewer: Ctrl-C will not save the image (no signal handler: {e})");
            }
        });
        *INTERRUPT_TARGET.lock().unwrap_or_else(std::sync::PoisonError::into_inner) = Some(proxy);
        Self
    }
}

impl Drop for Interrupts {
    fn drop(&mut self) {
        *INTERRUPT_TARGET.lock().unwrap_or_else(std::sync::PoisonError::into_inner) = None;
    }
}

fn no_window(e: impl std::fmt::Display) -> anyhow::Error {
    // winit's OS errors read "os error at FILE:LINE: message"; keep the message.
    let text = e.to_string();
    let message = text.strip_prefix("os error at ").and_then(|r| r.split_once(": ")).map_or(text.as_str(), |(_, m)| m);
    anyhow!("cannot open a window: {message} (set DISPLAY, or run under xvfb-run)")
}

/// Mouse state between events.
#[derive(Default)]
struct Input {
    orbiting: bool,
    panning_right: bool,
    panning_middle: bool,
    cursor: Option<PhysicalPosition<f64>>,
    modifiers: ModifiersState,
}

/// Totals over all frames, and since the title was last written.
#[derive(Default)]
struct Counters {
    frames: u32,
    samples: u64,
    time: Duration,
    recent_samples: u64,
    recent_time: Duration,
    frames_on_device: u32,
}

impl Counters {
    fn rate(&self) -> f64 {
        if self.time.is_zero() { 0.0 } else { self.samples as f64 / self.time.as_secs_f64() }
    }
}

/// How often the title bar is rewritten.
const TITLE_INTERVAL: Duration = Duration::from_millis(250);

struct App {
    scene: Arc<dyn PreparedScene>,
    settings: RenderSettings,
    options: ViewerOptions,
    control: CameraControl,
    /// The render thread (it owns the running render: on the device for the GPU backend,
    /// whose frames it draws onto the window itself through a wgpu surface).
    worker: Worker,
    /// The view the window shows: frames of older views are dropped.
    generation: u64,
    /// Samples per pixel of the image on screen.
    spp: u32,
    /// Whether the worker is still refining the view (as of its last frame).
    refining: bool,
    /// The image on screen, 0RGB, where frames come to the CPU.
    pixels: Vec<u32>,
    window: Option<Arc<Window>>,
    surface: Option<softbuffer::Surface<Arc<Window>, Arc<Window>>>,
    /// Whether the last frame shown was put on the window by the render thread (through
    /// its wgpu surface) rather than into `pixels`.
    on_screen: bool,
    /// Whether the render thread is to draw the frames (it has not said it cannot): the
    /// window then draws nothing itself, so that softbuffer never draws over its surface.
    awaiting_device: bool,
    /// Whether Ctrl-C or SIGTERM ended the session.
    interrupted: bool,
    input: Input,
    stats: Counters,
    title_at: Option<Instant>,
    title_rate: f64,
    error: Option<anyhow::Error>,
}

impl App {
    fn refining(&self) -> bool {
        self.refining
    }

    /// The settings of the current view: the window's size, the user's camera, the
    /// render's whole sample budget (for samplers that lay samples out for it).
    fn view_settings(&self) -> RenderSettings {
        let budget = self.options.max_spp.unwrap_or(self.options.spp_per_frame);
        RenderSettings { spp: budget, camera: Some(self.control.camera()), ..self.settings.clone() }
    }

    /// Starts a new view on the worker; `preview` asks for a quick quarter-size frame first.
    fn new_view(&mut self, preview: bool) {
        self.generation += 1;
        self.refining = true;
        self.worker.send(Command::View { generation: self.generation, settings: self.view_settings(), preview });
    }

    fn fail(&mut self, event_loop: &ActiveEventLoop, e: anyhow::Error) {
        self.error.get_or_insert(e);
        event_loop.exit();
    }

    fn open(&mut self, event_loop: &ActiveEventLoop) -> anyhow::Result<()> {
        let attributes = Window::default_attributes()
            .with_title(format!("spt — {}", self.options.title))
            .with_inner_size(PhysicalSize::new(self.settings.width, self.settings.height));
        let window = Arc::new(event_loop.create_window(attributes).map_err(no_window)?);
        let context = softbuffer::Context::new(window.clone()).map_err(no_window)?;
        let surface = softbuffer::Surface::new(&context, window.clone()).map_err(no_window)?;
        if self.options.device_display {
            // The GPU backend's render thread takes the window over with a wgpu surface
            // (other backends' ignore this); until it does, frames come here.
            self.worker.send(Command::Present(window.clone()));
        }
        self.window = Some(window.clone());
        self.surface = Some(surface);
        let size = window.inner_size();
        self.resize(size.width, size.height);
        window.request_redraw();
        Ok(())
    }

    /// Renders at a new image size (from the next frame on).
    fn resize(&mut self, width: u32, height: u32) {
        let (width, height) = (width.min(MAX_IMAGE_SIDE), height.min(MAX_IMAGE_SIDE));
        if width == 0 || height == 0 || (width, height) == (self.settings.width, self.settings.height) {
            return;
        }
        self.settings.width = width;
        self.settings.height = height;
        self.pixels = vec![0; width as usize * height as usize];
        self.new_view(false);
    }

    /// Restarts the render after a camera move, with a quick preview first.
    fn moved(&mut self) {
        self.new_view(true);
    }

    /// Shows a frame from the worker (if it belongs to the current view), scaled to the
    /// window where it is a preview.
    fn show(&mut self, frame: Frame) {
        self.stats.frames = frame.frames;
        self.stats.recent_samples += frame.samples - self.stats.samples;
        self.stats.recent_time += frame.time.saturating_sub(self.stats.time);
        self.stats.samples = frame.samples;
        self.stats.time = frame.time;
        self.stats.frames_on_device = frame.frames_on_device;
        if let Pixels::Host(_) = frame.pixels {
            self.awaiting_device = false;
        }
        if frame.generation != self.generation {
            return;
        }
        self.on_screen = matches!(frame.pixels, Pixels::OnScreen);
        // Else the render thread drew it on the window already.
        if let Pixels::Host(pixels) = &frame.pixels {
            let (w, h) = (self.settings.width as usize, self.settings.height as usize);
            let (fw, fh) = (frame.width as usize, frame.height as usize);
            if (fw, fh) == (w, h) {
                self.pixels.copy_from_slice(pixels);
            } else if fw > 0 && fh > 0 {
                // Nearest neighbour: a preview (or a frame of the size before a resize).
                for y in 0..h {
                    let row = &pixels[(y * fh / h) * fw..][..fw];
                    for (x, p) in self.pixels[y * w..][..w].iter_mut().enumerate() {
                        *p = row[x * fw / w];
                    }
                }
            }
        }
        if !frame.preview {
            self.spp = frame.spp;
            self.refining = frame.refining;
        }
    }

    fn update_title(&mut self, force: bool) {
        let now = Instant::now();
        if !force && self.title_at.is_some_and(|t| now - t < TITLE_INTERVAL) {
            return;
        }
        if !self.stats.recent_time.is_zero() {
            self.title_rate = self.stats.recent_samples as f64 / self.stats.recent_time.as_secs_f64();
        }
        self.stats.recent_samples = 0;
        self.stats.recent_time = Duration::ZERO;
        self.title_at = Some(now);
        let done = if self.refining() { "" } else { " — done" };
        let title = format!(
            "spt — {} — {} spp, {:.2} M samples/s ({}){done}",
            self.options.title,
            self.spp,
            self.title_rate / 1e6,
            self.scene.capabilities().backend
        );
        if let Some(w) = &self.window {
            w.set_title(&title);
        }
    }

    fn present(&mut self) -> anyhow::Result<()> {
        if self.on_screen {
            self.worker.send(Command::Redraw);
            return Ok(());
        }
        if self.awaiting_device {
            return Ok(());
        }
        let Some(surface) = self.surface.as_mut() else { return Ok(()) };
        let (w, h) = (self.settings.width, self.settings.height);
        let (Some(nw), Some(nh)) = (NonZeroU32::new(w), NonZeroU32::new(h)) else { return Ok(()) };
        surface.resize(nw, nh).map_err(|e| anyhow!("cannot resize the window's buffer: {e}"))?;
        let mut buffer = surface.buffer_mut().map_err(|e| anyhow!("cannot draw in the window: {e}"))?;
        if buffer.len() == self.pixels.len() {
            buffer.copy_from_slice(&self.pixels);
        }
        buffer.present().map_err(|e| anyhow!("cannot draw in the window: {e}"))
    }

    fn redraw(&mut self, event_loop: &ActiveEventLoop) {
        if let Err(e) = self.present() {
            self.fail(event_loop, e);
        }
    }

    /// A frame is waiting (or the worker failed): show it and decide whether to quit.
    fn frame_arrived(&mut self, event_loop: &ActiveEventLoop) {
        let Some(frame) = self.worker.take() else { return };
        let frame = match frame {
            Ok(f) => f,
            Err(e) => return self.fail(event_loop, e),
        };
        let was_refining = self.refining;
        self.show(frame);
        self.update_title(was_refining && !self.refining);
        // A frame the render thread drew on the window needs no redraw here.
        if let Some(w) = self.window.as_ref().filter(|_| !self.on_screen) {
            w.request_redraw();
        }
        if let Some(n) = self.options.exit_after_frames
            && (self.stats.frames >= n || !self.refining)
        {
            self.update_title(true);
            event_loop.exit();
        }
    }

    /// Writes the current mean image, PNG or EXR by extension (the worker writes it
    /// between frames).
    fn save(&mut self, path: &Path) -> anyhow::Result<()> {
        let spp = self.worker.save(path.to_path_buf())?;
        eprintln!("saved {} ({spp} spp)", path.display());
        Ok(())
    }

    fn key(&mut self, event_loop: &ActiveEventLoop, event: &KeyEvent) {
        if event.state != ElementState::Pressed {
            return;
        }
        let fast = if self.input.modifiers.shift_key() { 5.0 } else { 1.0 };
        if let Key::Named(NamedKey::Escape) = event.logical_key {
            event_loop.exit();
            return;
        }
        if let PhysicalKey::Code(code) = event.physical_key
            && self.physical_key(code, fast)
        {
            return self.moved();
        }
        if let Key::Character(s) = &event.logical_key {
            match s.to_lowercase().as_str() {
                "+" | "=" => {
                    self.control.dolly(1.0);
                    self.moved();
                }
                "-" | "_" => {
                    self.control.dolly(-1.0);
                    self.moved();
                }
                "r" => {
                    self.control.reset();
                    self.moved();
                }
                "p" | "x" if !event.repeat => {
                    let ext = if s.eq_ignore_ascii_case("p") { "png" } else { "exr" };
                    let path = PathBuf::from(format!("spt-view-{}spp.{ext}", self.spp));
                    if let Err(e) = self.save(&path) {
                        eprintln!("cannot save the image: {e:#}");
                    }
                }
                _ => {}
            }
        }
    }

    /// Camera moves bound to key positions (WASD, QE, arrows, keypad ±), whatever the
    /// layout; true if `code` is one.
    fn physical_key(&mut self, code: KeyCode, fast: f32) -> bool {
        let turn = 5f32.to_radians() * fast;
        let c = &mut self.control;
        match code {
            KeyCode::KeyW => c.fly(fast, 0.0, 0.0),
            KeyCode::KeyS => c.fly(-fast, 0.0, 0.0),
            KeyCode::KeyA => c.fly(0.0, -fast, 0.0),
            KeyCode::KeyD => c.fly(0.0, fast, 0.0),
            KeyCode::KeyQ => c.fly(0.0, 0.0, -fast),
            KeyCode::KeyE => c.fly(0.0, 0.0, fast),
            KeyCode::ArrowLeft => c.turn(turn, 0.0),
            KeyCode::ArrowRight => c.turn(-turn, 0.0),
            KeyCode::ArrowUp => c.turn(0.0, turn),
            KeyCode::ArrowDown => c.turn(0.0, -turn),
            KeyCode::NumpadAdd => c.dolly(1.0),
            KeyCode::NumpadSubtract => c.dolly(-1.0),
            _ => return false,
        }
        true
    }

    fn cursor_moved(&mut self, position: PhysicalPosition<f64>) {
        let last = self.input.cursor.replace(position);
        let Some(last) = last else { return };
        let height = self.settings.height.max(1) as f64;
        let (dx, dy) = (((position.x - last.x) / height) as f32, ((position.y - last.y) / height) as f32);
        if dx == 0.0 && dy == 0.0 {
            return;
        }
        if self.input.orbiting {
            self.control.orbit(dx * std::f32::consts::PI, dy * std::f32::consts::PI);
            self.moved();
        } else if self.input.panning_right || self.input.panning_middle {
            self.control.pan(dx, dy);
            self.moved();
        }
    }
}

/// What other threads tell the window's event loop.
#[derive(Clone, Copy, Debug)]
enum Wake {
    /// The worker put a frame in its mailbox.
    Frame,
    /// Ctrl-C or SIGTERM: quit (saving, where asked to).
    Quit,
}

/// Divisor of the preview frames' width and height while the camera moves.
const PREVIEW_DIVISOR: u32 = 4;

impl ApplicationHandler<Wake> for App {
    fn user_event(&mut self, event_loop: &ActiveEventLoop, wake: Wake) {
        match wake {
            Wake::Frame => self.frame_arrived(event_loop),
            Wake::Quit => {
                eprintln!("viewer: interrupted, quitting");
                self.interrupted = true;
                event_loop.exit();
            }
        }
    }

    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        event_loop.set_control_flow(ControlFlow::Wait);
        if self.window.is_none()
            && let Err(e) = self.open(event_loop)
        {
            self.fail(event_loop, e);
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) => {
                self.resize(size.width, size.height);
                if let Some(w) = &self.window {
                    w.request_redraw();
                }
            }
            WindowEvent::RedrawRequested => self.redraw(event_loop),
            WindowEvent::ModifiersChanged(m) => self.input.modifiers = m.state(),
            WindowEvent::KeyboardInput { event, .. } => self.key(event_loop, &event),
            WindowEvent::MouseInput { state, button, .. } => {
                let pressed = state == ElementState::Pressed;
                match button {
                    MouseButton::Left => self.input.orbiting = pressed,
                    MouseButton::Right => self.input.panning_right = pressed,
                    MouseButton::Middle => self.input.panning_middle = pressed,
                    _ => {}
                }
            }
            WindowEvent::CursorMoved { position, .. } => self.cursor_moved(position),
            WindowEvent::CursorLeft { .. } => self.input.cursor = None,
            WindowEvent::MouseWheel { delta, .. } => {
                let steps = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => (p.y / 40.0) as f32,
                };
                if steps != 0.0 {
                    self.control.dolly(steps);
                    self.moved();
                }
            }
            _ => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn options_are_checked() {
        assert!(ViewerOptions::default().validate().is_ok());
        assert!(ViewerOptions { width: 0, ..Default::default() }.validate().is_err());
        assert!(ViewerOptions { spp_per_frame: 0, ..Default::default() }.validate().is_err());
        assert!(ViewerOptions { max_spp: Some(0), ..Default::default() }.validate().is_err());
        let beyond = Some(tracer::film::MAX_PIXEL_SAMPLES + 1);
        assert!(ViewerOptions { max_spp: beyond, ..Default::default() }.validate().is_err());
    }
}
