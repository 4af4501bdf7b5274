//! What crosses the display's lines, captured, and decoded back into pixels.
//!
//! A [`CaptureBus`] hands out an SPI device and two output pins (data/command
//! and frame-done) that record into one caller-provided buffer, as a logic
//! analyzer on those lines would:
//!
//! | record | bytes |
//! |---|---|
//! | bytes sent with data/command low | `C`, length (u16 LE), the bytes |
//! | bytes sent with data/command high | `D`, length (u16 LE), the bytes |
//! | frame-done rising / falling edge | `F` / `f` |
//!
//! [`decode`] replays a capture through a model of the controller and writes
//! the pixels into an image, so a test can check what the panel would show.
//!
//! ```
//! use terracast_board::{decode, rgb565, CaptureBus, SpiDisplay};
//!
//! // A 2 x 3 frame, row-major, as a kernel render into a framebuffer leaves it.
//! let frame: [[u8; 3]; 6] = core::array::from_fn(|i| [(i % 2 * 100) as u8, (i / 2 * 80) as u8, 7]);
//! let mut wire = [0u8; 256];
//! let bus = CaptureBus::new(&mut wire);
//! let mut display: SpiDisplay<_, _, _, 4> =
//!     SpiDisplay::new(bus.spi(), bus.data_command(), bus.frame_done(), 2, 3).unwrap();
//! display.send_frame(&frame).unwrap();
//! let _ = display.release();
//! let bytes = bus.into_written().unwrap();
//!
//! let mut image = [0u16; 6];
//! let decoded = decode(bytes, &mut image, 2, 3).unwrap();
//! assert_eq!(decoded.frames, 1);
//! assert_eq!(image[2 * 2 + 1], rgb565([100, 160, 7])); // x 1, y 2
//! ```

use crate::display::command;
use core::cell::RefCell;
use core::fmt;
use embedded_hal::digital::{self, OutputPin};
use embedded_hal::spi::{self, Operation, SpiDevice};

/// Record tag: bytes sent with data/command low.
pub const TAG_COMMAND: u8 = b'C';
/// Record tag: bytes sent with data/command high.
pub const TAG_DATA: u8 = b'D';
/// Record tag: the frame-done line rose.
pub const TAG_DONE_HIGH: u8 = b'F';
/// Record tag: the frame-done line fell.
pub const TAG_DONE_LOW: u8 = b'f';

/// Capture bytes of [`SpiDisplay::init`](crate::SpiDisplay::init): the
/// frame-done line set low, four commands and two one-byte parameters.
pub const INIT_CAPTURE_BYTES: usize = 1 + 4 * 4 + 2 * 4;

/// Capture bytes of a whole `width` × `height` frame through
/// [`SpiDisplay`](crate::SpiDisplay), its init included: size a capture
/// buffer with it.
pub const fn frame_capture_bytes(width: u32, height: u32) -> usize {
    let pixel_bytes = 2 * height as usize;
    // Records are at most u16::MAX bytes long.
    let pixel_records = pixel_bytes.div_ceil(u16::MAX as usize);
    // Two address commands (a command record and a 4-byte parameter
    // record each), the memory-write command, then the pixels.
    let column = 2 * (4 + 7) + 4 + 3 * pixel_records + pixel_bytes;
    INIT_CAPTURE_BYTES + width as usize * column + 2
}

/// Why a capture failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CaptureError {
    /// The capture buffer is full; the record was not written.
    Full,
    /// The bus was used from inside its own call (never by the driver).
    Busy,
    /// The SPI device was asked to read: a display is write-only.
    Read,
}

impl fmt::Display for CaptureError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Full => "capture buffer is full",
            Self::Busy => "capture bus used re-entrantly",
            Self::Read => "capture bus cannot read: the display is write-only",
        })
    }
}

impl core::error::Error for CaptureError {}

impl spi::Error for CaptureError {
    fn kind(&self) -> spi::ErrorKind {
        spi::ErrorKind::Other
    }
}

impl digital::Error for CaptureError {
    fn kind(&self) -> digital::ErrorKind {
        digital::ErrorKind::Other
    }
}

#[derive(Debug)]
struct Log<'b> {
    buffer: &'b mut [u8],
    len: usize,
    data_high: bool,
    failed: Option<CaptureError>,
}

impl Log<'_> {
    fn push(&mut self, bytes: &[u8]) -> Result<(), CaptureError> {
        let end = self.len + bytes.len();
        let Some(slot) = self.buffer.get_mut(self.len..end) else {
            self.failed = Some(CaptureError::Full);
            return Err(CaptureError::Full);
        };
        slot.copy_from_slice(bytes);
        self.len = end;
        Ok(())
    }

    fn record_bytes(&mut self, bytes: &[u8]) -> Result<(), CaptureError> {
        let tag = if self.data_high {
            TAG_DATA
        } else {
            TAG_COMMAND
        };
        for chunk in bytes.chunks(usize::from(u16::MAX)) {
            let [lo, hi] = (chunk.len() as u16).to_le_bytes();
            self.push(&[tag, lo, hi])?;
            self.push(chunk)?;
        }
        Ok(())
    }
}

/// The capture: owns the buffer, lends out the bus and pins.
#[derive(Debug)]
pub struct CaptureBus<'b> {
    log: RefCell<Log<'b>>,
}

impl<'b> CaptureBus<'b> {
    /// A capture into `buffer`, empty, data/command low.
    pub fn new(buffer: &'b mut [u8]) -> Self {
        Self {
            log: RefCell::new(Log {
                buffer,
                len: 0,
                data_high: false,
                failed: None,
            }),
        }
    }

    /// The SPI device: records each write.
    pub fn spi(&self) -> CaptureSpi<'_, 'b> {
        CaptureSpi { bus: self }
    }

    /// The data/command pin: sets the tag of the bytes that follow.
    pub fn data_command(&self) -> CapturePin<'_, 'b> {
        CapturePin {
            bus: self,
            line: Line::DataCommand,
        }
    }

    /// The frame-done pin: records each level it is set to.
    pub fn frame_done(&self) -> CapturePin<'_, 'b> {
        CapturePin {
            bus: self,
            line: Line::FrameDone,
        }
    }

    /// Bytes recorded so far.
    pub fn len(&self) -> usize {
        self.log.try_borrow().map(|log| log.len).unwrap_or(0)
    }

    /// Whether nothing was recorded.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The recorded bytes, or the error that cut the capture short.
    pub fn into_written(self) -> Result<&'b [u8], CaptureError> {
        let log = self.log.into_inner();
        if let Some(e) = log.failed {
            return Err(e);
        }
        let len = log.len;
        let buffer: &'b [u8] = log.buffer;
        Ok(buffer.get(..len).unwrap_or(&[]))
    }

    fn with<T>(
        &self,
        f: impl FnOnce(&mut Log<'b>) -> Result<T, CaptureError>,
    ) -> Result<T, CaptureError> {
        let mut log = self.log.try_borrow_mut().map_err(|_| CaptureError::Busy)?;
        f(&mut log)
    }
}

/// The capture's SPI device.
#[derive(Debug)]
pub struct CaptureSpi<'a, 'b> {
    bus: &'a CaptureBus<'b>,
}

impl spi::ErrorType for CaptureSpi<'_, '_> {
    type Error = CaptureError;
}

impl SpiDevice for CaptureSpi<'_, '_> {
    fn transaction(&mut self, operations: &mut [Operation<'_, u8>]) -> Result<(), CaptureError> {
        self.bus.with(|log| {
            for operation in operations.iter() {
                match operation {
                    Operation::Write(bytes) => log.record_bytes(bytes)?,
                    Operation::DelayNs(_) => {}
                    Operation::Read(_)
                    | Operation::Transfer(..)
                    | Operation::TransferInPlace(_) => return Err(CaptureError::Read),
                }
            }
            Ok(())
        })
    }
}

#[derive(Debug, Clone, Copy)]
enum Line {
    DataCommand,
    FrameDone,
}

/// One of the capture's output pins.
#[derive(Debug)]
pub struct CapturePin<'a, 'b> {
    bus: &'a CaptureBus<'b>,
    line: Line,
}

impl CapturePin<'_, '_> {
    fn set(&mut self, high: bool) -> Result<(), CaptureError> {
        let line = self.line;
        self.bus.with(|log| match line {
            Line::DataCommand => {
                log.data_high = high;
                Ok(())
            }
            Line::FrameDone => log.push(&[if high { TAG_DONE_HIGH } else { TAG_DONE_LOW }]),
        })
    }
}

impl digital::ErrorType for CapturePin<'_, '_> {
    type Error = CaptureError;
}

impl OutputPin for CapturePin<'_, '_> {
    fn set_low(&mut self) -> Result<(), CaptureError> {
        self.set(false)
    }

    fn set_high(&mut self) -> Result<(), CaptureError> {
        self.set(true)
    }
}

/// What a capture drew.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Decoded {
    /// Frame-done pulses (rising edges).
    pub frames: u32,
    /// Pixels written to display memory.
    pub pixels: u64,
}

/// Why a capture does not decode; `at` is the record's byte offset.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DecodeError {
    /// The capture ends inside a record.
    Truncated {
        /// Offset of the record.
        at: usize,
    },
    /// A record tag that is none of `C`, `D`, `F`, `f`.
    UnknownTag {
        /// Offset of the record.
        at: usize,
        /// The tag byte.
        tag: u8,
    },
    /// A command the controller model does not know.
    UnknownCommand {
        /// Offset of the record.
        at: usize,
        /// The command byte.
        command: u8,
    },
    /// A command's parameters are missing, too many, or out of range (an
    /// address window outside the image, a pixel format other than RGB565).
    BadParameters {
        /// Offset of the command's record.
        at: usize,
        /// The command.
        command: u8,
    },
    /// More pixels than the address window holds.
    PixelsBeyondWindow {
        /// Offset of the record.
        at: usize,
    },
    /// The image slice is shorter than width × height.
    ImageTooSmall,
}

impl fmt::Display for DecodeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::Truncated { at } => write!(f, "capture ends inside the record at byte {at}"),
            Self::UnknownTag { at, tag } => write!(f, "unknown record tag {tag:#04x} at byte {at}"),
            Self::UnknownCommand { at, command } => {
                write!(f, "unknown display command {command:#04x} at byte {at}")
            }
            Self::BadParameters { at, command } => {
                write!(
                    f,
                    "bad parameters for display command {command:#04x} at byte {at}"
                )
            }
            Self::PixelsBeyondWindow { at } => {
                write!(f, "more pixels than the address window holds at byte {at}")
            }
            Self::ImageTooSmall => f.write_str("image is smaller than width x height"),
        }
    }
}

impl core::error::Error for DecodeError {}

/// The controller model: the current command and its window.
struct Controller<'i> {
    image: &'i mut [u16],
    width: u32,
    height: u32,
    command: Option<u8>,
    /// Offset of the current command's record.
    command_at: usize,
    /// Parameter bytes of the current command (address commands take 4).
    parameters: [u8; 4],
    parameter_count: usize,
    columns: (u32, u32),
    rows: (u32, u32),
    /// Next pixel of a memory write, and a high byte waiting for its pair.
    cursor: (u32, u32),
    high_byte: Option<u8>,
    decoded: Decoded,
}

impl Controller<'_> {
    fn command(&mut self, at: usize, byte: u8) -> Result<(), DecodeError> {
        self.end_command()?;
        match byte {
            command::SLEEP_OUT
            | command::DISPLAY_ON
            | command::COLUMN_ADDRESS
            | command::PAGE_ADDRESS
            | command::MEMORY_ACCESS
            | command::PIXEL_FORMAT => {}
            command::MEMORY_WRITE => {
                self.cursor = (self.columns.0, self.rows.0);
                self.high_byte = None;
            }
            command => return Err(DecodeError::UnknownCommand { at, command }),
        }
        self.command = Some(byte);
        self.command_at = at;
        self.parameter_count = 0;
        Ok(())
    }

    /// Checks the parameters of the command that is ending.
    fn end_command(&mut self) -> Result<(), DecodeError> {
        let Some(command) = self.command else {
            return Ok(());
        };
        let at = self.command_at;
        let bad = Err(DecodeError::BadParameters { at, command });
        let [a, b, c, d] = self.parameters;
        let (first, last) = (
            u32::from(u16::from_be_bytes([a, b])),
            u32::from(u16::from_be_bytes([c, d])),
        );
        match command {
            command::COLUMN_ADDRESS | command::PAGE_ADDRESS => {
                let side = if command == command::COLUMN_ADDRESS {
                    self.width
                } else {
                    self.height
                };
                if self.parameter_count != 4 || first > last || last >= side {
                    return bad;
                }
                if command == command::COLUMN_ADDRESS {
                    self.columns = (first, last);
                } else {
                    self.rows = (first, last);
                }
            }
            command::PIXEL_FORMAT
                if self.parameter_count != 1 || a != command::PIXEL_FORMAT_RGB565 =>
            {
                return bad
            }
            command::MEMORY_ACCESS if self.parameter_count != 1 || a != 0 => return bad,
            command::MEMORY_WRITE if self.high_byte.is_some() => return bad,
            command::SLEEP_OUT | command::DISPLAY_ON if self.parameter_count != 0 => return bad,
            _ => {}
        }
        self.command = None;
        Ok(())
    }

    fn data(&mut self, at: usize, bytes: &[u8]) -> Result<(), DecodeError> {
        let Some(command) = self.command else {
            return Err(DecodeError::BadParameters { at, command: 0 });
        };
        if command != command::MEMORY_WRITE {
            for &byte in bytes {
                let slot = self
                    .parameters
                    .get_mut(self.parameter_count)
                    .ok_or(DecodeError::BadParameters { at, command })?;
                *slot = byte;
                self.parameter_count += 1;
            }
            return Ok(());
        }
        for &byte in bytes {
            let Some(high) = self.high_byte.take() else {
                self.high_byte = Some(byte);
                continue;
            };
            let (x, y) = self.cursor;
            if y > self.rows.1 {
                return Err(DecodeError::PixelsBeyondWindow { at });
            }
            let index = y as usize * self.width as usize + x as usize;
            if let Some(pixel) = self.image.get_mut(index) {
                *pixel = u16::from_be_bytes([high, byte]);
            }
            self.decoded.pixels += 1;
            self.cursor = if x < self.columns.1 {
                (x + 1, y)
            } else {
                (self.columns.0, y + 1)
            };
        }
        Ok(())
    }
}

/// Replays `capture` into `image` (row-major RGB565, `width` × `height`).
pub fn decode(
    capture: &[u8],
    image: &mut [u16],
    width: u32,
    height: u32,
) -> Result<Decoded, DecodeError> {
    if image.len() < width as usize * height as usize {
        return Err(DecodeError::ImageTooSmall);
    }
    let mut controller = Controller {
        image,
        width,
        height,
        command: None,
        command_at: 0,
        parameters: [0; 4],
        parameter_count: 0,
        columns: (0, width.saturating_sub(1)),
        rows: (0, height.saturating_sub(1)),
        cursor: (0, 0),
        high_byte: None,
        decoded: Decoded::default(),
    };
    let mut at = 0;
    while let Some(&tag) = capture.get(at) {
        match tag {
            TAG_DONE_HIGH => {
                controller.decoded.frames += 1;
                at += 1;
            }
            TAG_DONE_LOW => at += 1,
            TAG_COMMAND | TAG_DATA => {
                let truncated = DecodeError::Truncated { at };
                let length = capture.get(at + 1..at + 3).ok_or(truncated)?;
                let length = usize::from(u16::from_le_bytes([length[0], length[1]]));
                let bytes = capture.get(at + 3..at + 3 + length).ok_or(truncated)?;
                if tag == TAG_DATA {
                    controller.data(at, bytes)?;
                } else {
                    for &byte in bytes {
                        controller.command(at, byte)?;
                    }
                }
                at += 3 + length;
            }
            tag => return Err(DecodeError::UnknownTag { at, tag }),
        }
    }
    controller.end_command()?;
    Ok(controller.decoded)
}
