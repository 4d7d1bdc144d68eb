//! Images refined frame by frame, as an interactive viewer shows them.
//!
//! A viewer adds a few samples per pixel, shows the running mean and repeats; after a
//! camera move it starts over. Through [`PreparedScene::render_pass`] every frame would
//! hand the backend a [`Film`] and get it back updated — for the GPU, a read-back of
//! 32 bytes per pixel and a merge into the film's exact sums on the CPU (66 MB and about
//! 170 ms per 1080p frame on an H100 machine, 40× the samples' own time on the Cornell
//! box). An [`Accumulation`] lets the backend keep the running statistics where it
//! renders: a frame costs its samples plus the display conversion, and the exact film is
//! only assembled when asked for ([`Accumulation::film`], e.g. to save).
//!
//! [`PreparedScene::accumulate`] makes one; its default, [`FilmAccumulation`], renders
//! passes into a film (what the CPU needs: its film already lives where it renders);
//! the GPU backend keeps its accumulators on the device.

use crate::film::{Film, MAX_PIXEL_SAMPLES};
use crate::integrator::PathCounters;
use crate::render::{Capabilities, PreparedScene, RenderSettings};
use crate::{Error, Result};
use std::sync::Arc;

/// A running render of one view: passes of samples added in order, shown as they come.
pub trait Accumulation: Send {
    /// Samples per pixel added since the last (re)start.
    fn samples(&self) -> u32;

    /// The settings of the view being refined.
    fn settings(&self) -> &RenderSettings;

    /// Starts over with `settings` (a moved camera, a resized window): no samples.
    /// `settings.spp` is the render's whole sample budget (samplers that lay samples out
    /// for it use it), not a frame's.
    fn restart(&mut self, settings: &RenderSettings) -> Result<()>;

    /// Adds samples `samples() .. samples() + spp` of every pixel. It may return before
    /// the backend has finished them; [`display`](Self::display) and
    /// [`film`](Self::film) wait.
    fn add(&mut self, spp: u32) -> Result<()>;

    /// The running mean as 0x00RRGGBB pixels (sRGB-encoded, clamped; row-major), the
    /// layout of softbuffer and of [`Film::display_pixels`]; `out` has one element per
    /// pixel.
    fn display(&mut self, out: &mut [u32]) -> Result<()>;

    /// The samples so far as a film: the same statistics `render_pass` would have
    /// given for the same samples.
    fn film(&mut self) -> Result<Film>;

    /// Rays traced and paths cut since the last (re)start.
    fn counters(&mut self) -> Result<PathCounters>;

    /// The accumulation itself, for a caller that knows its backend and can use more of
    /// it than this trait offers (a viewer drawing the GPU's frames onto a window surface
    /// from the device: `gpu::accumulation::DeviceAccumulation`). `None` (the default):
    /// only this trait.
    fn as_any_mut(&mut self) -> Option<&mut dyn std::any::Any> {
        None
    }
}

/// Checks what an accumulation of a scene prepared with `capabilities` is asked to
/// render: valid settings within the backend's reach, the whole image.
pub fn check_accumulation_settings(capabilities: &Capabilities, settings: &RenderSettings) -> Result<()> {
    settings.validate()?;
    capabilities.check_settings(settings)?;
    if settings.crop.is_some() {
        return Err(Error::Setting("an accumulation refines the whole image: it takes no crop window".into()));
    }
    Ok(())
}

/// The [`Accumulation`] any backend can give: passes rendered into a [`Film`] on the
/// CPU.
pub struct FilmAccumulation<S: PreparedScene + ?Sized> {
    scene: Arc<S>,
    settings: RenderSettings,
    film: Film,
    samples: u32,
    counters: PathCounters,
}

impl<S: PreparedScene + ?Sized> FilmAccumulation<S> {
    /// An empty accumulation of `scene` seen with `settings`.
    pub fn new(scene: Arc<S>, settings: &RenderSettings) -> Result<Self> {
        check_accumulation_settings(&scene.capabilities(), settings)?;
        Ok(Self {
            film: Film::new(settings.width, settings.height),
            scene,
            settings: settings.clone(),
            samples: 0,
            counters: PathCounters::default(),
        })
    }
}

impl<S: PreparedScene + ?Sized> Accumulation for FilmAccumulation<S> {
    fn samples(&self) -> u32 {
        self.samples
    }

    fn settings(&self) -> &RenderSettings {
        &self.settings
    }

    fn restart(&mut self, settings: &RenderSettings) -> Result<()> {
        check_accumulation_settings(&self.scene.capabilities(), settings)?;
        if (settings.width, settings.height) == (self.film.width(), self.film.height()) {
            self.film.clear();
        } else {
            self.film = Film::new(settings.width, settings.height);
        }
        self.settings = settings.clone();
        self.samples = 0;
        self.counters = PathCounters::default();
        Ok(())
    }

    fn add(&mut self, spp: u32) -> Result<()> {
        let spp = spp.min(MAX_PIXEL_SAMPLES - self.samples);
        if spp == 0 {
            return Ok(());
        }
        self.counters += self.scene.render_pass(&self.settings, &mut self.film, self.samples, spp, &|_| {})?;
        self.samples += spp;
        Ok(())
    }

    fn display(&mut self, out: &mut [u32]) -> Result<()> {
        self.film.display_pixels(out);
        Ok(())
    }

    fn film(&mut self) -> Result<Film> {
        Ok(self.film.clone())
    }

    fn counters(&mut self) -> Result<PathCounters> {
        Ok(self.counters)
    }
}
