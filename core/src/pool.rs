//! The line pool: image lines handed out one at a time to any number of
//! workers, across frames (Cohen-Or §3.2 hands out columns; the caster's
//! unit is the image line through the vertical's vanishing point, which is
//! a column at pitch 0).
//!
//! Each worker takes a line, renders it with [`render_line`], and takes
//! the next. When the last line of a frame has been taken, the next take
//! returns the first line of the next frame, as soon as the master has
//! [published](LinePool::publish) that frame's view: no worker waits for
//! the slowest line of a frame. The pool's state is two numbers behind a
//! [`critical_section::Mutex`], so the same code serves a single-core board
//! (interrupts masked), a multi-core one, and host threads (with
//! `critical-section`'s `std` implementation).
//!
//! ```
//! use terracast::{LinePool, Task};
//!
//! let pool = LinePool::new(3, 2); // 3 lines a frame, 2 frames
//! pool.publish(0);
//! assert_eq!(pool.take(), Ok(Task { frame: 0, line: 0 }));
//! assert_eq!(pool.take(), Ok(Task { frame: 0, line: 1 }));
//! assert_eq!(pool.take(), Ok(Task { frame: 0, line: 2 }));
//! // Frame 1's view is not set up yet: come back later.
//! assert_eq!(pool.take(), Err(terracast::Wait::NotPublished { frame: 1 }));
//! pool.publish(1);
//! assert_eq!(pool.take(), Ok(Task { frame: 1, line: 0 }));
//! ```
//!
//! [`render_line`]: crate::render_line

use core::cell::Cell;
use critical_section::Mutex;

/// One unit of work: a line of a frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Task {
    /// Frame number, from 0.
    pub frame: u32,
    /// Image line (see [`View::lines`](crate::View::lines)).
    pub line: u32,
}

/// Why [`LinePool::take`] gave no line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Wait {
    /// The next line belongs to `frame`, whose view the master has not
    /// published yet.
    NotPublished {
        /// The frame waited for.
        frame: u32,
    },
    /// Every line of every frame has been taken.
    Finished,
}

#[derive(Debug, Clone, Copy)]
struct State {
    next: Task,
    /// Frames `0..published` may be taken.
    published: u32,
}

/// Lines of `frames` frames of `lines` lines each, taken in order. Frames
/// of one image size have different numbers of lines; size the pool with
/// [`max_lines`](crate::max_lines) and let the lines past a frame's last
/// render nothing.
#[derive(Debug)]
pub struct LinePool {
    state: Mutex<Cell<State>>,
    lines: u32,
    frames: u32,
}

impl LinePool {
    /// A pool for `frames` frames of `lines` lines; nothing published.
    pub const fn new(lines: u32, frames: u32) -> Self {
        Self {
            state: Mutex::new(Cell::new(State {
                next: Task { frame: 0, line: 0 },
                published: 0,
            })),
            lines,
            frames,
        }
    }

    /// Lines a frame.
    pub fn lines(&self) -> u32 {
        self.lines
    }

    /// Frames in all.
    pub fn frames(&self) -> u32 {
        self.frames
    }

    /// The master has set up `frame`'s view: its lines (and those of
    /// every earlier frame) may be taken.
    pub fn publish(&self, frame: u32) {
        critical_section::with(|cs| {
            let cell = self.state.borrow(cs);
            let mut state = cell.get();
            state.published = state.published.max(frame.saturating_add(1));
            cell.set(state);
        });
    }

    /// The next line, in frame order then line order.
    pub fn take(&self) -> Result<Task, Wait> {
        critical_section::with(|cs| {
            let cell = self.state.borrow(cs);
            let mut state = cell.get();
            let task = state.next;
            if task.frame >= self.frames || self.lines == 0 {
                return Err(Wait::Finished);
            }
            if task.frame >= state.published {
                return Err(Wait::NotPublished { frame: task.frame });
            }
            state.next = if task.line + 1 < self.lines {
                Task {
                    frame: task.frame,
                    line: task.line + 1,
                }
            } else {
                Task {
                    frame: task.frame + 1,
                    line: 0,
                }
            };
            cell.set(state);
            Ok(task)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_line_of_every_frame_is_taken_once_in_order() {
        let pool = LinePool::new(4, 3);
        pool.publish(2);
        let mut taken = std::vec::Vec::new();
        while let Ok(task) = pool.take() {
            taken.push((task.frame, task.line));
        }
        let expected: std::vec::Vec<_> = (0..3).flat_map(|f| (0..4).map(move |c| (f, c))).collect();
        assert_eq!(taken, expected);
        assert_eq!(pool.take(), Err(Wait::Finished));
    }

    #[test]
    fn threads_share_the_pool_without_losing_or_repeating_a_line() {
        let pool = LinePool::new(97, 5);
        pool.publish(4);
        let mut all: std::vec::Vec<Task> = std::thread::scope(|scope| {
            let workers: std::vec::Vec<_> = (0..4)
                .map(|_| {
                    scope.spawn(|| {
                        let mut mine = std::vec::Vec::new();
                        while let Ok(task) = pool.take() {
                            mine.push(task);
                        }
                        mine
                    })
                })
                .collect();
            workers
                .into_iter()
                .flat_map(|w| w.join().unwrap())
                .collect()
        });
        all.sort_by_key(|t| (t.frame, t.line));
        assert_eq!(all.len(), 97 * 5);
        for (i, task) in all.iter().enumerate() {
            assert_eq!((task.frame, task.line), ((i / 97) as u32, (i % 97) as u32));
        }
    }

    #[test]
    fn empty_pools_are_finished() {
        assert_eq!(LinePool::new(0, 3).take(), Err(Wait::Finished));
        let none = LinePool::new(5, 0);
        none.publish(0);
        assert_eq!(none.take(), Err(Wait::Finished));
    }
}
