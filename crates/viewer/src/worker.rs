//! The render worker: a thread that owns the running render ([`Accumulation`]) and turns
//! out frames, so that the window's event loop never waits for one — input is handled
//! while a slow frame (a CPU frame of a large scene takes a second) is still rendering.
//!
//! The window thread sends [`Command`]s (a new view, a save, quit); the worker leaves
//! each finished [`Frame`] in a one-slot mailbox (a newer frame replaces one not yet
//! shown, so a slow window never queues frames up) and wakes the event loop. After a
//! camera move the worker first renders one preview frame at a quarter of the size
//! (resolution scaling while moving: dragging stays fluid), then refines at full size.
//!
//! On the GPU backend the worker also owns the window's wgpu surface once the window
//! hands it over ([`Command::Present`]): it draws each frame from the device onto the
//! window itself and tells the window only that it did ([`Pixels::OnScreen`]). The
//! surface lives on this thread because wgpu configures a surface (at creation, at each
//! resize) only while no other thread submits work to the device, and this thread is the
//! one that submits.

use crate::PREVIEW_DIVISOR;
use anyhow::{Context as _, anyhow};
use gpu::accumulation::DeviceAccumulation;
use std::path::PathBuf;
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender, TryRecvError};
use std::sync::{Arc, Mutex, PoisonError};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};
use tracer::{Accumulation, PreparedScene, RenderSettings};

/// What the window asks of the worker.
pub(crate) enum Command {
    /// Start over with these settings (camera, size); `generation` tags the frames of this
    /// view; `preview` asks for one quarter-size frame first.
    View { generation: u64, settings: RenderSettings, preview: bool },
    /// Write the current image (PNG or EXR by extension); the reply says how many samples
    /// per pixel it held.
    Save(PathBuf, Sender<anyhow::Result<u32>>),
    /// Draw frames onto this window through a wgpu surface on the GPU backend's device
    /// (ignored on other backends; where the surface cannot be made, frames keep coming
    /// as pixels, and the reason is printed).
    Present(Arc<winit::window::Window>),
    /// Draw the last frame onto the window again (it was exposed).
    Redraw,
}

/// A frame's pixels.
pub(crate) enum Pixels {
    /// 0x00RRGGBB, row-major, for the window to show.
    Host(Vec<u32>),
    /// Already drawn on the window from the device.
    OnScreen,
}

/// A finished frame and the session's totals.
pub(crate) struct Frame {
    /// The view it belongs to.
    pub generation: u64,
    pub width: u32,
    pub height: u32,
    pub pixels: Pixels,
    /// Samples per pixel of the view so far (0 for a preview).
    pub spp: u32,
    /// A quarter-size frame shown while the camera moves.
    pub preview: bool,
    /// Whether the worker goes on refining this view.
    pub refining: bool,
    /// Full-size frames rendered in the session, samples taken and time spent on them.
    pub frames: u32,
    /// Full-size frames of the session drawn on the window from the device (not skipped).
    pub frames_on_device: u32,
    pub samples: u64,
    pub time: Duration,
}

type Mailbox = Arc<Mutex<Option<anyhow::Result<Frame>>>>;

/// The window thread's handle on the worker.
pub(crate) struct Worker {
    commands: Option<Sender<Command>>,
    mailbox: Mailbox,
    thread: Option<JoinHandle<()>>,
}

/// How the worker renders: samples per frame, where refining stops, when to stop
/// rendering frames at all.
#[derive(Clone, Copy)]
pub(crate) struct Pace {
    pub spp_per_frame: u32,
    pub max_spp: u32,
    pub max_frames: Option<u32>,
    /// Render nothing until the window's [`Command::Present`] (the GPU backend's frames
    /// are then all drawn from the device, none read back first).
    pub await_window: bool,
}

impl Worker {
    /// Starts the worker on `accumulation` (already started with the first view) of
    /// `scene`; `wake` is called after every frame put in the mailbox.
    pub fn start(
        scene: Arc<dyn PreparedScene>,
        accumulation: Box<dyn Accumulation>,
        pace: Pace,
        wake: impl Fn() + Send + 'static,
    ) -> anyhow::Result<Self> {
        let (commands, received) = mpsc::channel();
        let mailbox: Mailbox = Arc::new(Mutex::new(None));
        let slot = Arc::clone(&mailbox);
        let thread = std::thread::Builder::new()
            .name("spt-view-render".into())
            .spawn(move || {
                let mut state = State::new(scene, accumulation, pace);
                if let Err(e) = state.run(&received, &slot, &wake) {
                    *slot.lock().unwrap_or_else(PoisonError::into_inner) = Some(Err(e));
                    wake();
                }
            })
            .context("cannot start the render thread")?;
        Ok(Self { commands: Some(commands), mailbox, thread: Some(thread) })
    }

    /// Sends `command` (a stopped worker's error comes through the mailbox).
    pub fn send(&self, command: Command) {
        if let Some(c) = &self.commands {
            let _ = c.send(command);
        }
    }

    /// The newest frame, if one arrived since the last call (or the worker's error).
    pub fn take(&self) -> Option<anyhow::Result<Frame>> {
        self.mailbox.lock().unwrap_or_else(PoisonError::into_inner).take()
    }

    /// Saves the current image through the worker and waits for it.
    pub fn save(&self, path: PathBuf) -> anyhow::Result<u32> {
        let (reply, answer) = mpsc::channel();
        self.send(Command::Save(path, reply));
        answer.recv().map_err(|_| anyhow!("the render thread stopped before saving"))?
    }
}

impl Drop for Worker {
    /// Closes the command channel (the worker's signal to stop) and waits for it.
    fn drop(&mut self) {
        self.commands = None;
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// The worker thread's side.
struct State {
    scene: Arc<dyn PreparedScene>,
    main: Box<dyn Accumulation>,
    preview: Option<Box<dyn Accumulation>>,
    pace: Pace,
    generation: u64,
    preview_pending: bool,
    /// Whether the worker waits for the window's [`Command::Present`] before its first
    /// frame (the GPU backend's frames then all go to the surface, none to the CPU).
    awaiting_window: bool,
    /// The window's surface on the GPU backend's device.
    screen: Option<Screen>,
    frames: u32,
    frames_on_device: u32,
    samples: u64,
    time: Duration,
}

impl State {
    fn new(scene: Arc<dyn PreparedScene>, main: Box<dyn Accumulation>, pace: Pace) -> Self {
        Self {
            scene,
            main,
            preview: None,
            pace,
            generation: 0,
            preview_pending: false,
            awaiting_window: pace.await_window,
            screen: None,
            frames: 0,
            frames_on_device: 0,
            samples: 0,
            time: Duration::ZERO,
        }
    }

    fn refining(&self) -> bool {
        self.main.samples() < self.pace.max_spp && self.pace.max_frames.is_none_or(|n| self.frames < n)
    }

    fn run(&mut self, commands: &Receiver<Command>, mailbox: &Mailbox, wake: &dyn Fn()) -> anyhow::Result<()> {
        loop {
            // Commands first (all that are waiting); with nothing to render, wait for one
            // (and try again, now and then, to show a frame the window skipped).
            loop {
                let busy = !self.awaiting_window && (self.refining() || self.preview_pending);
                let command = if busy {
                    match commands.try_recv() {
                        Ok(c) => c,
                        Err(TryRecvError::Empty) => break,
                        Err(TryRecvError::Disconnected) => return Ok(()),
                    }
                } else if self.screen.as_ref().is_some_and(|s| s.skipped) {
                    match commands.recv_timeout(RETRY_SKIPPED) {
                        Ok(c) => c,
                        Err(RecvTimeoutError::Timeout) => {
                            self.redraw()?;
                            continue;
                        }
                        Err(RecvTimeoutError::Disconnected) => return Ok(()),
                    }
                } else {
                    match commands.recv() {
                        Ok(c) => c,
                        Err(_) => return Ok(()),
                    }
                };
                self.command(command)?;
            }
            let frame = if self.preview_pending { self.preview_frame()? } else { self.frame()? };
            *mailbox.lock().unwrap_or_else(PoisonError::into_inner) = Some(Ok(frame));
            wake();
        }
    }

    fn command(&mut self, command: Command) -> anyhow::Result<()> {
        let backend = self.scene.capabilities().backend;
        match command {
            Command::View { generation, settings, preview } => {
                self.generation = generation;
                self.main.restart(&settings).with_context(|| format!("{backend} backend"))?;
                self.preview_pending = preview;
                if let Some(screen) = &mut self.screen {
                    screen.surface.resize(settings.width, settings.height).context("resizing the window surface")?;
                }
            }
            Command::Save(path, reply) => {
                let saved = self.main.film().and_then(|film| {
                    tracer::output::write_image(&path, film.width(), film.height(), &film.mean_rgb())?;
                    Ok(self.main.samples())
                });
                let _ = reply.send(saved.map_err(anyhow::Error::from));
            }
            Command::Present(window) => {
                self.awaiting_window = false;
                let Some(device) = DeviceAccumulation::of(self.main.as_mut()) else {
                    if backend != "cpu" {
                        eprintln!(
                            "viewer: frames read back to a CPU framebuffer (this render's film is kept on the CPU by the \
                             {backend} backend)"
                        );
                    }
                    return Ok(());
                };
                let settings = device.settings();
                let (width, height) = (settings.width, settings.height);
                match gpu::present::WindowSurface::new(device.context(), window, width, height) {
                    Ok(surface) => {
                        eprintln!(
                            "viewer: frames drawn from the GPU's device through a wgpu surface ({})",
                            surface.describe()
                        );
                        self.screen = Some(Screen { surface, shown: None, skipped: false });
                    }
                    Err(e) => eprintln!("viewer: frames read back to a CPU framebuffer (no wgpu surface: {e})"),
                }
            }
            Command::Redraw => self.redraw()?,
        }
        Ok(())
    }

    /// The running mean of the main accumulation (`preview`: of the preview's): where the
    /// worker has the window's surface, made on the device as the frame to draw next
    /// ([`Pixels::OnScreen`] once [`State::redraw`] drew it), else read back.
    fn made(&mut self, preview: bool) -> anyhow::Result<Pixels> {
        let accumulation = if preview { self.preview.as_deref_mut() } else { Some(self.main.as_mut()) }
            .ok_or_else(|| anyhow!("no preview to show"))?;
        if let Some(screen) = &mut self.screen
            && let Some(device) = DeviceAccumulation::of(accumulation)
        {
            screen.shown = Some(device.display_frame()?);
            return Ok(Pixels::OnScreen);
        }
        let settings = accumulation.settings();
        let mut pixels = vec![0; settings.width as usize * settings.height as usize];
        accumulation.display(&mut pixels)?;
        Ok(Pixels::Host(pixels))
    }

    /// Draws the last device frame onto the window again (remembering whether the window
    /// skipped it).
    fn redraw(&mut self) -> anyhow::Result<()> {
        if let Some(screen) = &mut self.screen
            && let Some(frame) = &screen.shown
        {
            let presented = screen.surface.present(frame).context("drawing in the window")?;
            screen.skipped = presented == gpu::present::Presented::Skipped;
        }
        Ok(())
    }

    /// One full-size frame of the current view.
    fn frame(&mut self) -> anyhow::Result<Frame> {
        let backend = self.scene.capabilities().backend;
        let settings = self.main.settings().clone();
        let spp = self.pace.spp_per_frame.min(self.pace.max_spp - self.main.samples());
        let start = Instant::now();
        self.main.add(spp).with_context(|| format!("{backend} backend"))?;
        let pixels = self.made(false).with_context(|| format!("{backend} backend"))?;
        // The frame's time is its render's; drawing it on the window comes after.
        self.time += start.elapsed();
        if let Pixels::OnScreen = pixels {
            self.redraw()?;
            self.frames_on_device += u32::from(self.screen.as_ref().is_some_and(|s| !s.skipped));
        }
        self.samples += settings.width as u64 * settings.height as u64 * spp as u64;
        self.frames += 1;
        Ok(Frame {
            generation: self.generation,
            width: settings.width,
            height: settings.height,
            pixels,
            spp: self.main.samples(),
            preview: false,
            refining: self.refining(),
            frames: self.frames,
            frames_on_device: self.frames_on_device,
            samples: self.samples,
            time: self.time,
        })
    }

    /// One frame at a quarter of the size, from its own accumulation, one sample per pixel.
    fn preview_frame(&mut self) -> anyhow::Result<Frame> {
        self.preview_pending = false;
        let backend = self.scene.capabilities().backend;
        let full = self.main.settings();
        let settings = RenderSettings {
            width: full.width.div_ceil(PREVIEW_DIVISOR),
            height: full.height.div_ceil(PREVIEW_DIVISOR),
            spp: 1,
            ..full.clone()
        };
        let preview = match &mut self.preview {
            Some(p) => {
                p.restart(&settings)?;
                p
            }
            None => self.preview.insert(Arc::clone(&self.scene).accumulate(&settings)?),
        };
        preview.add(1).with_context(|| format!("{backend} backend"))?;
        let pixels = self.made(true).with_context(|| format!("{backend} backend"))?;
        if let Pixels::OnScreen = pixels {
            self.redraw()?;
        }
        Ok(Frame {
            generation: self.generation,
            width: settings.width,
            height: settings.height,
            pixels,
            spp: 0,
            preview: true,
            refining: true,
            frames: self.frames,
            frames_on_device: self.frames_on_device,
            samples: self.samples,
            time: self.time,
        })
    }
}

/// The window's wgpu surface, owned by the worker.
struct Screen {
    surface: gpu::present::WindowSurface,
    /// The frame last put on the window (kept for redraws; the accumulation does not
    /// write into it while it is held).
    shown: Option<gpu::present::DeviceFrame>,
    /// Whether the window skipped `shown` (minimised, a timeout): drawn again later.
    skipped: bool,
}

/// How often an idle worker tries again to show a frame the window skipped.
const RETRY_SKIPPED: Duration = Duration::from_millis(100);

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Condvar;
    use tracer::film::Film;
    use tracer::integrator::PathCounters;
    use tracer::render::{Capabilities, PrepareStats};
    use tracer::{Backend, CpuBackend, Material, SceneOptions};

    /// A prepared scene whose passes wait until the test opens a gate: a frame that never
    /// ends until the test says so.
    struct Gated {
        inner: Box<dyn PreparedScene>,
        open: Mutex<bool>,
        opened: Condvar,
    }

    impl PreparedScene for Gated {
        fn capabilities(&self) -> Capabilities {
            self.inner.capabilities()
        }
        fn scene(&self) -> &tracer::Scene {
            self.inner.scene()
        }
        fn bounds(&self) -> bvh::Aabb {
            self.inner.bounds()
        }
        fn stats(&self) -> PrepareStats {
            self.inner.stats()
        }
        fn render_pass(
            &self,
            settings: &RenderSettings,
            film: &mut Film,
            first_sample: u32,
            spp: u32,
            progress: &(dyn Fn(u64) + Sync),
        ) -> tracer::Result<PathCounters> {
            let mut open = self.open.lock().unwrap();
            while !*open {
                open = self.opened.wait(open).unwrap();
            }
            drop(open);
            self.inner.render_pass(settings, film, first_sample, spp, progress)
        }
    }

    /// The window's side never waits for a frame: while the worker is stuck inside one,
    /// a new view is sent and the mailbox is read at once. Once the frame ends, the new
    /// view's preview (a quarter of the size) comes before its full frames, the samples
    /// per pixel count up to the maximum, and a save goes through the worker.
    #[test]
    fn the_window_never_waits_and_previews_come_first() {
        let grey = Material::diffuse("grey", spectral::spectrum::Colour::constant(0.5)).unwrap();
        let inner = CpuBackend::new(1)
            .unwrap()
            .prepare(tracer::scenes::material_sphere(grey), &SceneOptions::default())
            .unwrap();
        let scene = Arc::new(Gated { inner, open: Mutex::new(false), opened: Condvar::new() });
        let settings = RenderSettings { width: 16, height: 12, spp: 1, ..RenderSettings::default() };
        let accumulation = (Arc::clone(&scene) as Arc<dyn PreparedScene>).accumulate(&settings).unwrap();
        let (woke, wakes) = mpsc::channel();
        let pace = Pace { spp_per_frame: 1, max_spp: 4, max_frames: None, await_window: false };
        let worker = Worker::start(scene.clone(), accumulation, pace, move || {
            let _ = woke.send(());
        })
        .unwrap();

        // The worker is inside its first frame, held at the gate.
        let moved = RenderSettings { seed: 9, ..settings.clone() };
        worker.send(Command::View { generation: 1, settings: moved, preview: true });
        assert!(worker.take().is_none(), "no frame can have finished behind a closed gate");

        *scene.open.lock().unwrap() = true;
        scene.opened.notify_all();
        let mut seen = Vec::new();
        while seen.last().is_none_or(|f: &(u64, bool, u32, u32, bool)| f.4) {
            wakes.recv().unwrap();
            if let Some(frame) = worker.take() {
                let f = frame.unwrap();
                seen.push((f.generation, f.preview, f.width, f.spp, f.refining));
            }
        }
        let current: Vec<_> = seen.iter().filter(|f| f.0 == 1).collect();
        assert_eq!(*current[0], (1, true, 4, 0, true), "the preview first, at a quarter of the width: {seen:?}");
        assert_eq!(current.last().map(|f| (f.2, f.3, f.4)), Some((16, 4, false)), "{seen:?}");
        let dir = std::env::temp_dir().join(format!("spt-view-worker-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let png = dir.join("saved.png");
        assert_eq!(worker.save(png.clone()).unwrap(), 4);
        assert!(png.exists());
        assert!(worker.save(dir.join("no-such-dir").join("x.png")).is_err(), "a failed save is reported");
    }
}
