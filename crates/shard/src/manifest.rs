//! What a partial render is a part of: the [`Job`] (everything that decides a pixel's
//! value) and the [`Manifest`] (the job plus which samples of which pixels the file holds).

use crate::plan::{ShardSpec, Work};
use crate::{Error, Result};
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use tracer::Scene;
use tracer::camera::Camera;
use tracer::render::{Capabilities, RenderSettings, SceneOptions};

/// The version of the partial format this build writes and reads.
pub const FORMAT_VERSION: u32 = 1;

/// A camera as written in a manifest (exact: f32s survive JSON unchanged).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CameraRecord {
    /// Eye position.
    pub eye: [f32; 3],
    /// The point looked at.
    pub center: [f32; 3],
    /// Up direction.
    pub up: [f32; 3],
    /// Vertical field of view, degrees.
    pub fov_y_deg: f32,
}

impl From<Camera> for CameraRecord {
    fn from(c: Camera) -> Self {
        Self { eye: c.eye.to_array(), center: c.center.to_array(), up: c.up.to_array(), fov_y_deg: c.fov_y_deg }
    }
}

/// Everything that decides the value of a pixel sample: two partials merge only if their
/// jobs are equal. (The thread count and the BVH width are absent: they do not change a
/// bit of the image.) Every field is written, none skipped at a default, so that two
/// jobs' JSON objects have the same keys ([`Job::differences`]); a field added later takes
/// a serde default for the partials written before it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Job {
    /// The program and its version (with the commit it was built from, where known):
    /// another build may trace differently.
    pub tool: String,
    /// SHA-256 of the scene's content ([`scene_hash`]), not of its file name.
    pub scene_sha256: String,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Samples per pixel of the whole render.
    pub spp: u32,
    /// The seed of every random stream.
    pub seed: u64,
    /// Spectral mode.
    pub spectral: String,
    /// Sampler.
    pub sampler: String,
    /// Maximum path depth (0: unbounded).
    pub max_depth: u32,
    /// Bounces before Russian roulette.
    pub rr_depth: u32,
    /// Russian roulette's scale of the survival probability (partials written before the
    /// field existed were rendered with 1, and read so).
    #[serde(default = "one_f32")]
    pub rr_scale: f32,
    /// Extra specular bounces.
    pub extension: u32,
    /// The limit on diffuse bounces (0: none; partials written before the field existed
    /// had none, and read so).
    #[serde(default)]
    pub max_diffuse_depth: u32,
    /// Shading-normal mode.
    pub shading_normals: String,
    /// Ray–triangle test.
    pub triangle_test: String,
    /// Backend (cpu, gpu): they round differently.
    pub backend: String,
    /// Integrator.
    pub integrator: String,
    /// The camera the render uses (the settings', the scene's or the default framing).
    pub camera: CameraRecord,
}

impl Job {
    /// The job of rendering `scene` with `settings` on a backend with `capabilities`,
    /// seen through `camera`, by the program `tool`.
    pub fn new(
        tool: &str,
        scene: &Scene,
        settings: &RenderSettings,
        options: &SceneOptions,
        capabilities: &Capabilities,
        camera: Camera,
    ) -> Self {
        Self {
            tool: tool.to_string(),
            scene_sha256: scene_hash(scene),
            width: settings.width,
            height: settings.height,
            spp: settings.spp,
            seed: settings.seed,
            spectral: settings.mode.name().into(),
            sampler: settings.sampler.name().into(),
            max_depth: settings.path.max_depth,
            rr_depth: settings.path.rr_depth,
            rr_scale: settings.path.rr_scale,
            extension: settings.path.specular_extension,
            max_diffuse_depth: settings.path.max_diffuse_depth,
            shading_normals: settings.path.shading_normals.name().into(),
            triangle_test: options.triangle_test.name().into(),
            backend: capabilities.backend.into(),
            integrator: capabilities.integrator.into(),
            camera: camera.into(),
        }
    }

    /// The fields in which `other` differs from this job, as `name: this ≠ other`.
    pub fn differences(&self, other: &Job) -> Vec<String> {
        let (a, b) = (serde_json::to_value(self), serde_json::to_value(other));
        let (Ok(serde_json::Value::Object(a)), Ok(serde_json::Value::Object(b))) = (a, b) else {
            return vec!["(unreadable job)".into()];
        };
        // Both serialise every field (none is skipped), so the keys are the same.
        a.iter().filter(|(k, v)| b.get(*k) != Some(v)).map(|(k, v)| format!("{k}: {v} ≠ {}", b[k])).collect()
    }
}

/// A partial render's description, stored as JSON at the head of its file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    /// [`FORMAT_VERSION`].
    pub format: u32,
    /// The scene as it was named on the command line (for messages only; the job's hash
    /// identifies the content).
    pub scene: String,
    /// What is rendered.
    pub job: Job,
    /// The shard this piece is, if the render was sharded.
    pub shard: Option<ShardSpec>,
    /// The pixels and samples this piece was asked for.
    pub work: Work,
    /// The backend's [`Capabilities::sample_block`] the shards were planned with.
    pub sample_block: u32,
    /// Samples `work.samples.start .. done` of every pixel of `work.region` are in the
    /// file; `done == work.samples.end` when the piece is complete.
    pub done: u32,
    /// Samples dropped as NaN, infinite or out of range (written from the film's count
    /// by [`crate::Partial::write`]; read into it by [`crate::partial::Reader::add_into`]).
    pub non_finite: u64,
    /// Rays traced.
    pub rays: u64,
    /// Light paths traced (bidirectional path tracing, whose light paths splat anywhere
    /// on the image): when non-zero, the file holds the whole image's splat sums after
    /// its pixels. Absent (0) in partials of other integrators.
    #[serde(default, skip_serializing_if = "is_zero_u64")]
    pub light_paths: u64,
}

fn one_f32() -> f32 {
    1.0
}

fn is_zero_u64(v: &u64) -> bool {
    *v == 0
}

impl Manifest {
    /// Whether every sample of the piece is in the file.
    pub fn complete(&self) -> bool {
        self.done == self.work.samples.end
    }

    /// The sample range the file holds.
    pub fn done_samples(&self) -> std::ops::Range<u32> {
        self.work.samples.start..self.done
    }

    /// A short description: `shard 2/4 by samples: samples 16..32 of 512×512 at (0, 0)`.
    pub fn describe(&self) -> String {
        let shard = self.shard.map_or("render".to_string(), |s| s.to_string());
        format!("{shard}: {}", Work { samples: self.done_samples(), ..self.work.clone() })
    }

    /// How far the piece got: `samples 0..14 of 0..64 done`.
    pub fn progress(&self) -> String {
        let s = &self.work.samples;
        format!("samples {}..{} of {}..{} done", s.start, self.done, s.start, s.end)
    }

    /// Checks the manifest's own consistency (region inside the image, sample ranges in
    /// order and within the render's spp, a supported format).
    pub fn validate(&self) -> Result<(), String> {
        if self.format != FORMAT_VERSION {
            return Err(format!("format version {} (this build reads {FORMAT_VERSION})", self.format));
        }
        let job = &self.job;
        if !self.work.region.fits(job.width, job.height) {
            return Err(format!("region {} outside the {}×{} image", self.work.region, job.width, job.height));
        }
        let s = &self.work.samples;
        if s.start > s.end || s.end > job.spp || self.done < s.start || self.done > s.end {
            return Err(format!("samples {}..{} (done to {}) outside 0..{}", s.start, s.end, self.done, job.spp));
        }
        if job.spp > tracer::film::MAX_PIXEL_SAMPLES {
            return Err(format!("{} samples per pixel (at most {})", job.spp, tracer::film::MAX_PIXEL_SAMPLES));
        }
        Ok(())
    }
}

/// SHA-256 (hex) of what a scene renders: its vertex, normal, tangent, triangle and
/// material-id arrays byte for byte, and its shapes, materials, camera and environment
/// as their exact `Debug` text (f32s print with enough digits to round-trip). Custom
/// BSDFs are opaque: two scenes that differ only in one hash alike.
pub fn scene_hash(scene: &Scene) -> String {
    let mut h = Sha256::new();
    let mut section = |name: &str, bytes: &[u8]| {
        h.update(name.as_bytes());
        h.update((bytes.len() as u64).to_le_bytes());
        h.update(bytes);
    };
    section("positions", bytemuck::cast_slice(&scene.positions));
    section("normals", bytemuck::cast_slice(&scene.normals));
    section("tangents", bytemuck::cast_slice(&scene.tangents));
    section("triangles", bytemuck::cast_slice(&scene.triangles));
    section("material_ids", bytemuck::cast_slice(&scene.material_ids));
    section("shapes", format!("{:?}", scene.shapes).as_bytes());
    section("materials", format!("{:?}", scene.materials).as_bytes());
    section("camera", format!("{:?}", scene.camera).as_bytes());
    section("environment", format!("{:?}", scene.environment).as_bytes());
    section("punctual_lights", format!("{:?}", scene.punctual_lights).as_bytes());
    hex(&h.finalize())
}

/// Lower-case hex.
pub(crate) fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// Checks that every manifest belongs to the same job as the first, naming the files
/// and the fields that differ.
pub(crate) fn same_job<'a>(items: impl IntoIterator<Item = (&'a std::path::Path, &'a Manifest)>) -> Result<()> {
    let mut items = items.into_iter();
    let Some((first_path, first)) = items.next() else { return Ok(()) };
    for (path, m) in items {
        let diff = first.job.differences(&m.job);
        if !diff.is_empty() {
            return Err(Error::Mismatch(format!(
                "{} and {} are parts of different renders ({}): render every shard with the same scene, \
                 settings and build",
                first_path.display(),
                path.display(),
                diff.join("; ")
            )));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn job() -> Job {
        Job {
            tool: "spt 0.1.0".into(),
            scene_sha256: "00".into(),
            width: 4,
            height: 3,
            spp: 8,
            seed: 0,
            spectral: "hero".into(),
            sampler: "zsobol".into(),
            max_depth: 0,
            rr_depth: 3,
            rr_scale: 1.0,
            extension: 0,
            max_diffuse_depth: 0,
            shading_normals: "adapted".into(),
            triangle_test: "watertight".into(),
            backend: "cpu".into(),
            integrator: "path".into(),
            camera: CameraRecord { eye: [0.0; 3], center: [0.0, 0.0, -1.0], up: [0.0, 1.0, 0.0], fov_y_deg: 40.0 },
        }
    }

    /// Fields at their defaults in one job and not in the other differ, in either order
    /// (they were once left out of a job's JSON: a walk over the first job's fields then
    /// missed one order and panicked on the other).
    #[test]
    fn differences_see_every_field_in_either_order() {
        let a = job();
        assert!(a.differences(&a.clone()).is_empty());
        let b = Job { rr_scale: 2.0, max_diffuse_depth: 2, ..job() };
        assert_eq!(a.differences(&b), ["max_diffuse_depth: 0 ≠ 2", "rr_scale: 1.0 ≠ 2.0"]);
        assert_eq!(b.differences(&a), ["max_diffuse_depth: 2 ≠ 0", "rr_scale: 2.0 ≠ 1.0"]);
    }

    /// A partial written before `max_diffuse_depth` and `rr_scale` existed reads as what
    /// it was rendered with: no diffuse limit, roulette scale 1.
    #[test]
    fn a_job_from_before_the_roulette_scale_reads_as_scale_one() {
        let mut old = serde_json::to_value(Job { rr_scale: 3.0, max_diffuse_depth: 2, ..job() }).unwrap();
        let fields = old.as_object_mut().unwrap();
        assert!(fields.remove("rr_scale").is_some() && fields.remove("max_diffuse_depth").is_some());
        let read: Job = serde_json::from_value(old).unwrap();
        assert_eq!((read.rr_scale, read.max_diffuse_depth), (1.0, 0));
    }
}
