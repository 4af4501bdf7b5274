//! The line pool on the host's real cores: each thread takes image lines
//! from the kernel's [`LinePool`] and renders them with [`render_line`],
//! frame after frame with no barrier between frames.

use crate::error::{Error, Result};
use crate::scene::KernelScene;
use std::time::Instant;
use terracast::{
    render_line, Camera, LinePool, NoProbe, RenderOptions, Rgb, Sample, Sink, Surface, View, Wait,
    WithDetail, WithSticks,
};

/// A worker's pixels of one frame, as they come: a line's pixels are
/// scattered over the image.
struct Pixels {
    frame: u32,
    put: Vec<(u32, u32, Rgb)>,
}

impl Sink for Pixels {
    fn put(&mut self, x: u32, y: u32, sample: Sample) {
        self.put.push((x, y, sample.color));
    }
}

/// Frames rendered by the pool and the wall time they took.
#[derive(Debug, Clone)]
pub struct ThreadedRun {
    /// Row-major colors of each frame.
    pub frames: Vec<Vec<Rgb>>,
    /// Wall time of the whole run, seconds.
    pub seconds: f64,
}

impl ThreadedRun {
    /// Millions of pixels a second.
    pub fn mpx_per_s(&self, size: (u32, u32)) -> f64 {
        let pixels = self.frames.len() as f64 * f64::from(size.0) * f64::from(size.1);
        pixels / self.seconds.max(1e-12) / 1e6
    }
}

/// Renders `cameras` with `threads` threads sharing one line pool. The
/// views are set up first (the master's work) and published at once.
pub fn render_threads(
    scene: &KernelScene,
    cameras: &[Camera],
    size: (u32, u32),
    options: &RenderOptions,
    threads: usize,
) -> Result<ThreadedRun> {
    if threads == 0 {
        return Err(Error::new("at least one thread is needed"));
    }
    let pyramid = scene.pyramid_for(options)?;
    let views = cameras
        .iter()
        .map(|c| View::new(c, size.0, size.1).map_err(|e| Error::new(format!("bad view: {e}"))))
        .collect::<Result<Vec<_>>>()?;
    let details = scene.details()?;
    Ok(match scene.sticks()? {
        Some(layer) => run(
            &WithSticks::new(&pyramid, layer),
            &views,
            size,
            options,
            threads,
        ),
        None if !details.is_empty() => run(
            &WithDetail::new(&pyramid, &details),
            &views,
            size,
            options,
            threads,
        ),
        None => run(&pyramid, &views, size, options, threads),
    })
}

/// [`render_threads`] on `surface`.
fn run<T: Surface + Sync + ?Sized>(
    surface: &T,
    views: &[View],
    size: (u32, u32),
    options: &RenderOptions,
    threads: usize,
) -> ThreadedRun {
    let lines = views.iter().map(View::lines).max().unwrap_or(0);
    let pool = LinePool::new(lines, views.len() as u32);
    let started = Instant::now();
    for frame in 0..views.len() as u32 {
        pool.publish(frame);
    }
    let done: Vec<Pixels> = std::thread::scope(|scope| {
        let workers: Vec<_> = (0..threads)
            .map(|_| {
                scope.spawn(|| {
                    let mut mine: Vec<Pixels> = Vec::new();
                    loop {
                        match pool.take() {
                            Ok(task) => {
                                if mine.last().is_none_or(|p| p.frame != task.frame) {
                                    mine.push(Pixels {
                                        frame: task.frame,
                                        put: Vec::new(),
                                    });
                                }
                                let Some(pixels) = mine.last_mut() else {
                                    continue;
                                };
                                let view = &views[task.frame as usize];
                                render_line(
                                    surface,
                                    view,
                                    options,
                                    task.line,
                                    pixels,
                                    &mut NoProbe,
                                );
                            }
                            Err(Wait::NotPublished { .. }) => std::thread::yield_now(),
                            Err(Wait::Finished) => break,
                        }
                    }
                    mine
                })
            })
            .collect();
        workers
            .into_iter()
            .flat_map(|w| w.join().unwrap_or_default())
            .collect()
    });
    let seconds = started.elapsed().as_secs_f64();
    let (w, h) = (size.0 as usize, size.1 as usize);
    let mut frames = vec![vec![[0u8; 3]; w * h]; views.len()];
    for pixels in done {
        let frame = &mut frames[pixels.frame as usize];
        for (x, y, color) in pixels.put {
            if let Some(pixel) = frame.get_mut(y as usize * w + x as usize) {
                *pixel = color;
            }
        }
    }
    ThreadedRun { frames, seconds }
}

#[cfg(test)]
mod tests {
    use super::*;
    use terracast::{render, Framebuffer};

    #[test]
    fn any_number_of_threads_renders_the_frames_render_does() {
        let bare = crate::scene::procedural(128, 5);
        let mut planted = bare.clone();
        planted.plant_objects(5);
        let options = RenderOptions::default();
        let cameras: Vec<Camera> = (0..3)
            .map(|i| terracast::Camera::looking([64.0, 10.0 + 5.0 * i as f32, 120.0], 90.0, 20.0))
            .collect();
        let size = (64, 48);
        let mut frames_of_each = Vec::new();
        for scene in [bare, planted] {
            let scene = scene.to_kernel().unwrap();
            let pyramid = scene.pyramid_for(&options).unwrap();
            let sticks = scene.sticks().unwrap();
            let expected: Vec<Vec<Rgb>> = cameras
                .iter()
                .map(|c| {
                    let mut colors = vec![[0u8; 3]; 64 * 48];
                    let mut fb = Framebuffer::new(&mut colors, 64, 48).unwrap();
                    let view = View::new(c, 64, 48).unwrap();
                    match sticks {
                        Some(layer) => render(
                            &WithSticks::new(&pyramid, layer),
                            &view,
                            &options,
                            &mut fb,
                            &mut NoProbe,
                        ),
                        None => render(&pyramid, &view, &options, &mut fb, &mut NoProbe),
                    }
                    colors
                })
                .collect();
            for threads in [1, 2, 5] {
                let run = render_threads(&scene, &cameras, size, &options, threads).unwrap();
                assert_eq!(run.frames, expected, "{threads} threads");
                assert!(run.mpx_per_s(size) > 0.0);
            }
            assert!(render_threads(&scene, &cameras, size, &options, 0).is_err());
            frames_of_each.push(expected);
        }
        assert_ne!(frames_of_each[0], frames_of_each[1], "the objects show");
    }
}
