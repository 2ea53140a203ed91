//! `vrao info`: the adapter and what it can do.

use vrao::{BackendChoice, Gpu, Result};

pub fn run(backend: BackendChoice) -> Result<()> {
    println!("{}", Gpu::new(backend)?.describe());
    Ok(())
}
