//! The column pool on the host's real cores: each thread takes columns from
//! the kernel's [`ColumnPool`] and renders them with
//! [`render_column`], frame after frame with no barrier between frames.

use crate::error::{Error, Result};
use crate::scene::KernelScene;
use std::time::Instant;
use terracast::{
    render_column, Camera, ColumnPool, NoProbe, RenderOptions, Rgb, Sample, Sink, View, Wait,
};

/// One column's pixels, top to bottom.
struct ColumnBuffer {
    colors: Vec<Rgb>,
}

impl Sink for ColumnBuffer {
    fn put(&mut self, _x: u32, y: u32, sample: Sample) {
        if let Some(pixel) = self.colors.get_mut(y as usize) {
            *pixel = sample.color;
        }
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

/// Renders `cameras` with `threads` threads sharing one column pool. The
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
    let pool = ColumnPool::new(size.0, views.len() as u32);
    let started = Instant::now();
    for frame in 0..views.len() as u32 {
        pool.publish(frame);
    }
    let done: Vec<(u32, u32, Vec<Rgb>)> = std::thread::scope(|scope| {
        let workers: Vec<_> = (0..threads)
            .map(|_| {
                scope.spawn(|| {
                    let mut mine = Vec::new();
                    loop {
                        match pool.take() {
                            Ok(task) => {
                                let mut column = ColumnBuffer {
                                    colors: vec![[0; 3]; size.1 as usize],
                                };
                                let view = &views[task.frame as usize];
                                render_column(
                                    &pyramid,
                                    view,
                                    options,
                                    task.column,
                                    &mut column,
                                    &mut NoProbe,
                                );
                                mine.push((task.frame, task.column, column.colors));
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
    for (frame, column, colors) in done {
        for (y, color) in colors.into_iter().enumerate() {
            frames[frame as usize][y * w + column as usize] = color;
        }
    }
    Ok(ThreadedRun { frames, seconds })
}

#[cfg(test)]
mod tests {
    use super::*;
    use terracast::{render, Framebuffer};

    #[test]
    fn any_number_of_threads_renders_the_frames_render_does() {
        let scene = crate::scene::procedural(128, 5).to_kernel().unwrap();
        let options = RenderOptions::default();
        let cameras: Vec<Camera> = (0..3)
            .map(|i| crate::camera::looking([64.0, 10.0 + 5.0 * i as f32, 120.0], 90.0, 20.0))
            .collect();
        let size = (64, 48);
        let pyramid = scene.pyramid_for(&options).unwrap();
        let expected: Vec<Vec<Rgb>> = cameras
            .iter()
            .map(|c| {
                let mut colors = vec![[0u8; 3]; 64 * 48];
                let mut fb = Framebuffer::new(&mut colors, 64, 48).unwrap();
                let view = View::new(c, 64, 48).unwrap();
                render(&pyramid, &view, &options, &mut fb, &mut NoProbe);
                colors
            })
            .collect();
        for threads in [1, 2, 5] {
            let run = render_threads(&scene, &cameras, size, &options, threads).unwrap();
            assert_eq!(run.frames, expected, "{threads} threads");
            assert!(run.mpx_per_s(size) > 0.0);
        }
        assert!(render_threads(&scene, &cameras, size, &options, 0).is_err());
    }
}
