//! A display driver: a frame streamed to an SPI display controller, column
//! by column.
//!
//! The controller speaks the ILI9341 command set (shared by the ST7789 and
//! most small TFT controllers): a command byte is sent with the data/command
//! line low, its parameters and pixels with it high. Each image column is
//! sent as its own one-pixel-wide window (`CASET`, `PASET`, `RAMWR`), top to
//! bottom, in 16-bit RGB565, most significant byte first. The driver holds
//! one column (`H` pixels, two bytes each) and sends it when the column is
//! complete.
//!
//! Pixels must arrive column by column (in any order within a column). The
//! kernel finishes pixels line by line through the vertical's vanishing
//! point, which are columns only at pitch 0, so a board renders into a
//! framebuffer and hands it over with [`SpiDisplay::send_frame`].
//!
//! The frame-done line goes high and back low after a frame's last column
//! has been sent: a logic analyzer (or the board's LED) sees one pulse per
//! frame.
//!
//! [`Sink::put`] cannot return an error, so the first bus or pin error is
//! kept, every later pixel is dropped, and [`SpiDisplay::finish`] returns it.

use core::fmt;
use embedded_hal::delay::DelayNs;
use embedded_hal::digital::{self, OutputPin};
use embedded_hal::spi::{self, SpiDevice};
use terracast::{Rgb, Sample, Sink};

/// Controller commands the driver sends (ILI9341 numbering).
pub mod command {
    /// Leave sleep mode; the controller needs 120 ms before the next command.
    pub const SLEEP_OUT: u8 = 0x11;
    /// Turn the panel on.
    pub const DISPLAY_ON: u8 = 0x29;
    /// Column address set: first and last column, 16 bits each.
    pub const COLUMN_ADDRESS: u8 = 0x2A;
    /// Page (row) address set: first and last row, 16 bits each.
    pub const PAGE_ADDRESS: u8 = 0x2B;
    /// Memory write: pixels follow, filling the window row by row.
    pub const MEMORY_WRITE: u8 = 0x2C;
    /// Memory access control: scan order; 0 = rows top to bottom, columns
    /// left to right, RGB.
    pub const MEMORY_ACCESS: u8 = 0x36;
    /// Pixel format; [`PIXEL_FORMAT_RGB565`] selects 16 bits a pixel.
    pub const PIXEL_FORMAT: u8 = 0x3A;
    /// The `PIXEL_FORMAT` parameter for RGB565 on both interfaces.
    pub const PIXEL_FORMAT_RGB565: u8 = 0x55;
}

/// A color in the panel's 16-bit format: 5 bits red, 6 green, 5 blue.
pub fn rgb565(color: Rgb) -> u16 {
    let [r, g, b] = color;
    (u16::from(r >> 3) << 11) | (u16::from(g >> 2) << 5) | u16::from(b >> 3)
}

/// Why the display did not get a frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DisplayError {
    /// The SPI bus failed.
    Bus(spi::ErrorKind),
    /// The data/command or frame-done pin failed.
    Pin(digital::ErrorKind),
    /// The image is taller than the driver's column buffer, or wider than
    /// the controller can address.
    ImageSize,
    /// A frame handed to [`SpiDisplay::send_frame`] has fewer colors than
    /// the image has pixels.
    FrameTooSmall,
}

impl fmt::Display for DisplayError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Bus(kind) => write!(f, "display SPI bus failed: {kind}"),
            Self::Pin(kind) => write!(f, "display pin failed: {kind}"),
            Self::FrameTooSmall => f.write_str("frame has fewer colors than width x height"),
            Self::ImageSize => {
                f.write_str("image is taller than the display column buffer or wider than 65535")
            }
        }
    }
}

impl core::error::Error for DisplayError {}

fn bus_error<E: spi::Error>(e: E) -> DisplayError {
    DisplayError::Bus(e.kind())
}

fn pin_error<E: digital::Error>(e: E) -> DisplayError {
    DisplayError::Pin(e.kind())
}

/// The display driver; `H` is the tallest column it can hold.
#[derive(Debug)]
pub struct SpiDisplay<SPI, DC, DONE, const H: usize> {
    spi: SPI,
    data_command: DC,
    frame_done: DONE,
    width: u16,
    height: u16,
    /// The column being filled, top row first, RGB565 big-endian.
    column: [[u8; 2]; H],
    /// Which image column `column` holds, and how many of its pixels arrived.
    filling: Option<(u16, u16)>,
    error: Option<DisplayError>,
}

impl<SPI, DC, DONE, const H: usize> SpiDisplay<SPI, DC, DONE, H>
where
    SPI: SpiDevice,
    DC: OutputPin,
    DONE: OutputPin,
{
    /// A driver for a `width` × `height` image. Fails if `height > H` or the
    /// width does not fit the controller's 16-bit addresses.
    pub fn new(
        spi: SPI,
        data_command: DC,
        frame_done: DONE,
        width: u32,
        height: u32,
    ) -> Result<Self, DisplayError> {
        let fits = height as usize <= H && height > 0 && width > 0;
        let (Ok(width), Ok(height), true) = (u16::try_from(width), u16::try_from(height), fits)
        else {
            return Err(DisplayError::ImageSize);
        };
        Ok(Self {
            spi,
            data_command,
            frame_done,
            width,
            height,
            column: [[0; 2]; H],
            filling: None,
            error: None,
        })
    }

    /// Wakes the controller and sets 16-bit pixels and the scan order.
    pub fn init(&mut self, delay: &mut impl DelayNs) -> Result<(), DisplayError> {
        self.frame_done.set_low().map_err(pin_error)?;
        self.command(command::SLEEP_OUT, &[])?;
        delay.delay_ms(120);
        self.command(command::PIXEL_FORMAT, &[command::PIXEL_FORMAT_RGB565])?;
        self.command(command::MEMORY_ACCESS, &[0])?;
        self.command(command::DISPLAY_ON, &[])
    }

    /// Sends a column left incomplete, pulses the frame-done line, and
    /// returns the first error of the frame (clearing it for the next one).
    pub fn finish(&mut self) -> Result<(), DisplayError> {
        if self.error.is_none() && self.filling.is_some() {
            let result = self.send_column();
            self.keep(result);
        }
        self.filling = None;
        if self.error.is_none() {
            let result = self
                .frame_done
                .set_high()
                .and_then(|()| self.frame_done.set_low())
                .map_err(pin_error);
            self.keep(result);
        }
        match self.error.take() {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }

    /// Sends a row-major frame of `width × height` colors (the driver's image
    /// size) column by column, then [finishes](Self::finish) it.
    pub fn send_frame(&mut self, colors: &[Rgb]) -> Result<(), DisplayError> {
        let (width, height) = (usize::from(self.width), usize::from(self.height));
        if colors.len() < width * height {
            return Err(DisplayError::FrameTooSmall);
        }
        for x in 0..width {
            for y in (0..height).rev() {
                let color = colors.get(y * width + x).copied().unwrap_or_default();
                self.put(
                    x as u32,
                    y as u32,
                    Sample {
                        color,
                        distance: 0,
                        elevation: 0,
                    },
                );
            }
        }
        self.finish()
    }

    /// Gives the bus and pins back.
    pub fn release(self) -> (SPI, DC, DONE) {
        (self.spi, self.data_command, self.frame_done)
    }

    fn keep(&mut self, result: Result<(), DisplayError>) {
        if let (Err(e), None) = (result, self.error) {
            self.error = Some(e);
        }
    }

    fn command(&mut self, command: u8, parameters: &[u8]) -> Result<(), DisplayError> {
        self.data_command.set_low().map_err(pin_error)?;
        self.spi.write(&[command]).map_err(bus_error)?;
        self.data_command.set_high().map_err(pin_error)?;
        if !parameters.is_empty() {
            self.spi.write(parameters).map_err(bus_error)?;
        }
        Ok(())
    }

    /// Sends the held column as a one-pixel-wide window.
    fn send_column(&mut self) -> Result<(), DisplayError> {
        let Some((x, _)) = self.filling else {
            return Ok(());
        };
        let [x_hi, x_lo] = x.to_be_bytes();
        let [y_hi, y_lo] = (self.height - 1).to_be_bytes();
        self.command(command::COLUMN_ADDRESS, &[x_hi, x_lo, x_hi, x_lo])?;
        self.command(command::PAGE_ADDRESS, &[0, 0, y_hi, y_lo])?;
        self.command(command::MEMORY_WRITE, &[])?;
        let pixels = self.column.get(..usize::from(self.height)).unwrap_or(&[]);
        self.spi.write(pixels.as_flattened()).map_err(bus_error)
    }
}

impl<SPI, DC, DONE, const H: usize> Sink for SpiDisplay<SPI, DC, DONE, H>
where
    SPI: SpiDevice,
    DC: OutputPin,
    DONE: OutputPin,
{
    fn put(&mut self, x: u32, y: u32, sample: Sample) {
        let (Ok(x), Ok(y)) = (u16::try_from(x), u16::try_from(y)) else {
            return;
        };
        if self.error.is_some() || x >= self.width || y >= self.height {
            return;
        }
        // A pixel of another column: the held one is finished (complete or
        // not, as columns arrive one at a time).
        if matches!(self.filling, Some((held, _)) if held != x) {
            let result = self.send_column();
            self.keep(result);
        }
        let arrived = match self.filling {
            Some((held, arrived)) if held == x => arrived,
            _ => 0,
        };
        if let Some(pixel) = self.column.get_mut(usize::from(y)) {
            *pixel = rgb565(sample.color).to_be_bytes();
        }
        self.filling = Some((x, arrived + 1));
        if arrived + 1 >= self.height {
            let result = self.send_column();
            self.keep(result);
            self.filling = None;
        }
    }
}
