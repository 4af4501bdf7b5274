//! # terracast-sim
//!
//! The host side of terracast: loads real terrain or generates a scene,
//! runs the `no_std` kernel on the host, renders the exact reference that
//! accuracy is measured against, and provides the `terracast-sim` command.
#![deny(missing_docs, unsafe_code)]

pub mod atmosphere;
pub mod baselines;
pub mod bench;
pub mod board;
pub mod camera;
pub mod chart;
pub mod cli;
pub mod error;
pub mod fit;
pub mod fly;
pub mod frame;
pub mod kernel;
pub mod metrics;
pub mod objects;
pub mod output;
pub mod outputs;
pub mod reference;
pub mod scene;
pub mod sim;
pub mod stability;
pub mod tiles;
pub mod viewer;
pub mod volume;

pub use error::{Error, Result};
