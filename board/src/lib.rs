//! # terracast-board
//!
//! What the terracast kernel needs to run on a board, beyond the kernel:
//!
//! - [`display`]: a driver that streams a rendered frame, column by column,
//!   to an SPI display controller (an ILI9341-style command set), written
//!   against the embedded-hal 1.0 traits: `SpiDevice` for pixels,
//!   `OutputPin` for data/command and for a frame-done line a logic analyzer
//!   can watch.
//! - [`wire`]: a capture of what crosses those lines (the bytes, each tagged
//!   with the data/command level, and the frame-done edges) into a
//!   caller-provided buffer, and a decoder that turns a capture back into an
//!   image the way the controller would. On the host the capture is the mock
//!   bus of the driver's tests; on the emulated board it is how the frame
//!   leaves the chip.
//! - [`governed`]: the governor's check: the cameras and the budget of a
//!   run of frames the board renders within one budget, as the host does.
//! - [`scene`]: the board scene file: a terrain and a list of views, packed by
//!   the host (`terracast-sim board scene`) and baked into the firmware.
//!
//! `no_std`, no allocator, no `unsafe`.
#![no_std]
#![deny(missing_docs, unsafe_code, missing_debug_implementations)]

pub mod display;
pub mod governed;
pub mod scene;
pub mod wire;

pub use display::{rgb565, DisplayError, SpiDisplay};
pub use scene::{BoardScene, SceneError};
pub use wire::{decode, CaptureBus, CaptureError, DecodeError, Decoded};
