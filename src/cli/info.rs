//! `vrao info`: the adapter and what it can do.

use vrao::Result;
use vrao_render::BackendChoice;

pub(crate) fn run(backend: BackendChoice) -> Result<()> {
    println!("{}", vrao_render::open(backend)?.describe());
    Ok(())
}
