//! What two-level instancing saves on the device: the GPU's buffers for a scene with
//! instances, traced two-level (each object once) against the same scene flattened into
//! one mesh. No device needed: it builds the upload on the CPU.
//!
//! ```sh
//! cargo run --release -p gpu --example instanced_upload -- scenes/bunnies.toml
//! ```

use gpu::backend::SceneData;
use gpu::kernel::KernelOptions;
use std::path::PathBuf;
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path: PathBuf = std::env::args_os().nth(1).map_or_else(|| "scenes/bunnies.toml".into(), PathBuf::from);
    let scene = tracer::scene_file::load_scene_file(&path)?;
    println!(
        "{}: {} triangles of its own, {} placed by {} instances of {} objects",
        path.display(),
        scene.triangles.len(),
        scene.instanced_triangle_count(),
        scene.instances.len(),
        scene.objects.len()
    );
    // As `GpuBackend::prepare_gpu` does: placements on area lights become world triangles.
    let mut two_level = scene.clone();
    two_level.flatten_light_instances();
    let mut flat = scene;
    flat.flatten_instances();
    for (name, scene) in [("two-level", two_level), ("flattened", flat)] {
        let start = Instant::now();
        let data = SceneData::new(&scene, KernelOptions::default())?;
        let elapsed = start.elapsed();
        let sizes = data.buffer_sizes();
        let total: u64 = sizes.iter().map(|(_, b)| b).sum();
        let geometry: u64 = sizes.iter().take(4).map(|(_, b)| b).sum();
        println!(
            "{name:>10}: {:.2} MB in all, {:.2} MB of nodes, vertices and attributes; built in {:.0} ms",
            total as f64 / 1e6,
            geometry as f64 / 1e6,
            elapsed.as_secs_f64() * 1e3
        );
    }
    Ok(())
}
