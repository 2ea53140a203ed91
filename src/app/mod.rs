//! The `vrao run` application: the headset frame loop, the budget governor, and the
//! desktop window with its panel. Builds on `render` and `xr`, never on `measure`.

mod buffer_view;
mod completion;
mod frame_loop;
pub mod governor;
mod headset;
mod history;
mod panel;
mod picture;
mod session;
mod summary;
pub mod window;

pub use buffer_view::BufferView;
pub use frame_loop::{FrameLoop, Step, SERIAL_EVERY};
pub use headset::{open_headset, HeadsetChoice, HeadsetError};
pub use history::PassHistory;
pub use session::{refresh_with_openxr, refused_summary, run_session, RunOptions, SessionError, RUN_FRAMES_MAX};
pub use summary::RunSummary;
