//! The SPI display driver on the capture bus, and the decoder: what the
//! panel would show, and every failure ending in an error value.

use embedded_hal::delay::DelayNs;
use terracast::{Sample, Sink};
use terracast_board::display::command;
use terracast_board::wire::{frame_capture_bytes, TAG_COMMAND, TAG_DATA};
use terracast_board::{decode, rgb565, CaptureBus, DecodeError, DisplayError, SpiDisplay};

struct NoDelay;

impl DelayNs for NoDelay {
    fn delay_ns(&mut self, _ns: u32) {}
}

fn sample(color: [u8; 3]) -> Sample {
    Sample {
        color,
        distance: 1,
        elevation: 0,
    }
}

fn color_at(x: u32, y: u32) -> [u8; 3] {
    [(x * 37) as u8, (y * 11) as u8, (x ^ y) as u8]
}

/// Streams a `width` × `height` frame, columns left to right, each bottom
/// to top, as `send_frame` does.
fn stream_frame<S: Sink>(sink: &mut S, width: u32, height: u32) {
    for x in 0..width {
        for y in (0..height).rev() {
            sink.put(x, y, sample(color_at(x, y)));
        }
    }
}

#[test]
fn rgb565_keeps_the_high_bits() {
    assert_eq!(rgb565([255, 255, 255]), 0xFFFF);
    assert_eq!(rgb565([255, 0, 0]), 0xF800);
    assert_eq!(rgb565([0, 255, 0]), 0x07E0);
    assert_eq!(rgb565([0, 0, 255]), 0x001F);
    assert_eq!(rgb565([7, 3, 7]), 0);
}

#[test]
fn two_frames_decode_to_what_was_drawn_with_one_pulse_each() {
    let (w, h) = (5, 7);
    let mut wire = vec![0u8; 2 * frame_capture_bytes(w, h)];
    let bus = CaptureBus::new(&mut wire);
    let mut display: SpiDisplay<_, _, _, 8> =
        SpiDisplay::new(bus.spi(), bus.data_command(), bus.frame_done(), w, h).unwrap();
    display.init(&mut NoDelay).unwrap();
    stream_frame(&mut display, w, h);
    display.finish().unwrap();
    // Out-of-range pixels are dropped, not drawn and not a panic.
    display.put(w, 0, sample([1, 2, 3]));
    display.put(0, h, sample([1, 2, 3]));
    stream_frame(&mut display, w, h);
    display.finish().unwrap();
    let _ = display.release();
    let bytes = bus.into_written().unwrap();
    assert_eq!(
        bytes.len(),
        frame_capture_bytes(w, h) * 2 - terracast_board::wire::INIT_CAPTURE_BYTES
    );

    let mut image = vec![0u16; (w * h) as usize];
    let decoded = decode(bytes, &mut image, w, h).unwrap();
    assert_eq!(decoded.frames, 2);
    assert_eq!(decoded.pixels, 2 * u64::from(w * h));
    for y in 0..h {
        for x in 0..w {
            assert_eq!(
                image[(y * w + x) as usize],
                rgb565(color_at(x, y)),
                "({x}, {y})"
            );
        }
    }
}

#[test]
fn an_unfinished_column_is_sent_when_the_next_begins_or_the_frame_ends() {
    let (w, h) = (3, 4);
    let mut wire = vec![0u8; 1024];
    let bus = CaptureBus::new(&mut wire);
    let mut display: SpiDisplay<_, _, _, 4> =
        SpiDisplay::new(bus.spi(), bus.data_command(), bus.frame_done(), w, h).unwrap();
    display.put(0, 3, sample([255, 0, 0]));
    display.put(1, 3, sample([0, 255, 0]));
    display.put(2, 0, sample([0, 0, 255]));
    display.finish().unwrap();
    let _ = display.release();
    let mut image = vec![0u16; 12];
    let decoded = decode(bus.into_written().unwrap(), &mut image, w, h).unwrap();
    assert_eq!(decoded.frames, 1);
    assert_eq!(image[9], 0xF800); // (0, 3)
    assert_eq!(image[10], 0x07E0); // (1, 3)
    assert_eq!(image[2], 0x001F); // (2, 0)
}

#[test]
fn a_full_bus_is_reported_by_finish_and_never_panics() {
    let mut wire = [0u8; 40];
    let bus = CaptureBus::new(&mut wire);
    let mut display: SpiDisplay<_, _, _, 16> =
        SpiDisplay::new(bus.spi(), bus.data_command(), bus.frame_done(), 8, 16).unwrap();
    stream_frame(&mut display, 8, 16);
    assert_eq!(
        display.finish(),
        Err(DisplayError::Bus(embedded_hal::spi::ErrorKind::Other))
    );
    // The error was handed out; the next frame starts clean but still
    // finds the bus full.
    stream_frame(&mut display, 8, 16);
    assert!(display.finish().is_err());
    let _ = display.release();
    assert!(bus.into_written().is_err());
}

#[test]
fn images_the_driver_cannot_hold_are_refused() {
    let mut wire = [0u8; 8];
    let bus = CaptureBus::new(&mut wire);
    let too_tall =
        SpiDisplay::<_, _, _, 16>::new(bus.spi(), bus.data_command(), bus.frame_done(), 8, 17);
    assert_eq!(too_tall.err(), Some(DisplayError::ImageSize));
    let too_wide =
        SpiDisplay::<_, _, _, 16>::new(bus.spi(), bus.data_command(), bus.frame_done(), 70_000, 8);
    assert_eq!(too_wide.err(), Some(DisplayError::ImageSize));
    let empty =
        SpiDisplay::<_, _, _, 16>::new(bus.spi(), bus.data_command(), bus.frame_done(), 0, 8);
    assert_eq!(empty.err(), Some(DisplayError::ImageSize));
}

/// A capture record by hand.
fn record(tag: u8, bytes: &[u8]) -> Vec<u8> {
    let mut out = vec![tag];
    out.extend_from_slice(&(bytes.len() as u16).to_le_bytes());
    out.extend_from_slice(bytes);
    out
}

#[test]
fn malformed_captures_are_named_errors() {
    let mut image = vec![0u16; 4 * 4];
    let mut decode_4x4 = |bytes: &[u8]| decode(bytes, &mut image, 4, 4);

    assert_eq!(
        decode_4x4(&[TAG_COMMAND, 5, 0, 1]),
        Err(DecodeError::Truncated { at: 0 })
    );
    assert_eq!(
        decode_4x4(b"x"),
        Err(DecodeError::UnknownTag { at: 0, tag: b'x' })
    );
    assert_eq!(
        decode_4x4(&record(TAG_COMMAND, &[0x99])),
        Err(DecodeError::UnknownCommand {
            at: 0,
            command: 0x99
        })
    );
    assert_eq!(
        decode_4x4(&record(TAG_DATA, &[1])),
        Err(DecodeError::BadParameters { at: 0, command: 0 })
    );
    // A column window past the image's right edge.
    let mut window = record(TAG_COMMAND, &[command::COLUMN_ADDRESS]);
    window.extend(record(TAG_DATA, &[0, 0, 0, 4]));
    assert_eq!(
        decode_4x4(&window),
        Err(DecodeError::BadParameters {
            at: 0,
            command: command::COLUMN_ADDRESS
        })
    );
    // 18-bit pixels are not what the driver sends.
    let mut format = record(TAG_COMMAND, &[command::PIXEL_FORMAT]);
    format.extend(record(TAG_DATA, &[0x66]));
    assert!(matches!(
        decode_4x4(&format),
        Err(DecodeError::BadParameters { .. })
    ));
    // Seventeen pixels into a 4 x 4 window.
    let mut flood = record(TAG_COMMAND, &[command::MEMORY_WRITE]);
    flood.extend(record(TAG_DATA, &[0xAB; 34]));
    assert_eq!(
        decode_4x4(&flood),
        Err(DecodeError::PixelsBeyondWindow { at: 4 })
    );
    // Half a pixel at the end.
    let mut half = record(TAG_COMMAND, &[command::MEMORY_WRITE]);
    half.extend(record(TAG_DATA, &[0xAB; 3]));
    assert!(matches!(
        decode_4x4(&half),
        Err(DecodeError::BadParameters { .. })
    ));
    assert_eq!(
        decode(&[], &mut [0u16; 3], 2, 2),
        Err(DecodeError::ImageTooSmall)
    );
}

#[test]
fn a_framebuffer_sent_whole_decodes_to_itself() {
    let (w, h) = (6, 4);
    let colors: Vec<[u8; 3]> = (0..w * h).map(|i| color_at(i % w, i / w)).collect();
    let mut wire = vec![0u8; frame_capture_bytes(w, h)];
    let bus = CaptureBus::new(&mut wire);
    let mut display: SpiDisplay<_, _, _, 4> =
        SpiDisplay::new(bus.spi(), bus.data_command(), bus.frame_done(), w, h).unwrap();
    display.init(&mut NoDelay).unwrap();
    // Too few colors for the image: refused before anything is sent.
    assert_eq!(
        display.send_frame(&colors[1..]),
        Err(DisplayError::FrameTooSmall)
    );
    display.send_frame(&colors).unwrap();
    let _ = display.release();
    let bytes = bus.into_written().unwrap();
    assert_eq!(bytes.len(), frame_capture_bytes(w, h));
    let mut image = vec![0u16; (w * h) as usize];
    let decoded = decode(bytes, &mut image, w, h).unwrap();
    assert_eq!(decoded.frames, 1);
    let expected: Vec<u16> = colors.iter().map(|&c| rgb565(c)).collect();
    assert_eq!(image, expected);
}
