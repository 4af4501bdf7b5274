//! Colors, as every layer of the kernel stores and blends them.

/// An 8-bit RGB color.
pub type Rgb = [u8; 3];
