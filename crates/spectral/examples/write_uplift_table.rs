//! Fits the RGB → spectrum uplift table and writes it where the `spectral` crate ships it
//! (`crates/spectral/data/uplift_srgb_32.bin`), or to the path given: run it after a change
//! to the fit, from the repository root:
//!
//! ```sh
//! cargo run --release -p spectral --example write_uplift_table
//! ```

use spectral::uplift::UpliftTable;
use std::path::PathBuf;

fn main() -> std::io::Result<()> {
    let path = std::env::args_os()
        .nth(1)
        .map_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data/uplift_srgb_32.bin"), PathBuf::from);
    let start = std::time::Instant::now();
    let bytes = UpliftTable::fit().to_bytes();
    std::fs::write(&path, &bytes)?;
    println!("fitted in {:.2?}; wrote {} ({} bytes)", start.elapsed(), path.display(), bytes.len());
    Ok(())
}
