//! The `vrao run` application: the headset frame loop, the budget governor, and the
//! desktop window with its panel. Builds on `render` and `xr`, never on `measure`.

mod frame_loop;
pub mod governor;
mod panel;
mod picture;
mod session;
pub mod window;

pub use frame_loop::*;
pub use session::{run_session, RunOptions};
