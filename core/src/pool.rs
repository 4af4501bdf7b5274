//! The column pool: image columns handed out one at a time to any number of
//! workers, across frames (Cohen-Or §3.2).
//!
//! Each worker takes a column, renders it with [`render_column`], and takes
//! the next. When the last column of a frame has been taken, the next take
//! returns the first column of the next frame, as soon as the master has
//! [published](ColumnPool::publish) that frame's view: no worker waits for
//! the slowest column of a frame. The pool's state is two numbers behind a
//! [`critical_section::Mutex`], so the same code serves a single-core board
//! (interrupts masked), a multi-core one, and host threads (with
//! `critical-section`'s `std` implementation).
//!
//! ```
//! use terracast::{ColumnPool, Task};
//!
//! let pool = ColumnPool::new(3, 2); // 3 columns a frame, 2 frames
//! pool.publish(0);
//! assert_eq!(pool.take(), Ok(Task { frame: 0, column: 0 }));
//! assert_eq!(pool.take(), Ok(Task { frame: 0, column: 1 }));
//! assert_eq!(pool.take(), Ok(Task { frame: 0, column: 2 }));
//! // Frame 1's view is not set up yet: come back later.
//! assert_eq!(pool.take(), Err(terracast::Wait::NotPublished { frame: 1 }));
//! pool.publish(1);
//! assert_eq!(pool.take(), Ok(Task { frame: 1, column: 0 }));
//! ```
//!
//! [`render_column`]: crate::render_column

use core::cell::Cell;
use critical_section::Mutex;

/// One unit of work: a column of a frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Task {
    /// Frame number, from 0.
    pub frame: u32,
    /// Image column.
    pub column: u32,
}

/// Why [`ColumnPool::take`] gave no column.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Wait {
    /// The next column belongs to `frame`, whose view the master has not
    /// published yet.
    NotPublished {
        /// The frame waited for.
        frame: u32,
    },
    /// Every column of every frame has been taken.
    Finished,
}

#[derive(Debug, Clone, Copy)]
struct State {
    next: Task,
    /// Frames `0..published` may be taken.
    published: u32,
}

/// Columns of `frames` frames of `width` columns each, taken in order.
#[derive(Debug)]
pub struct ColumnPool {
    state: Mutex<Cell<State>>,
    width: u32,
    frames: u32,
}

impl ColumnPool {
    /// A pool for `frames` frames of `width` columns; nothing published.
    pub const fn new(width: u32, frames: u32) -> Self {
        Self {
            state: Mutex::new(Cell::new(State {
                next: Task {
                    frame: 0,
                    column: 0,
                },
                published: 0,
            })),
            width,
            frames,
        }
    }

    /// Columns a frame.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Frames in all.
    pub fn frames(&self) -> u32 {
        self.frames
    }

    /// The master has set up `frame`'s view: its columns (and those of
    /// every earlier frame) may be taken.
    pub fn publish(&self, frame: u32) {
        critical_section::with(|cs| {
            let cell = self.state.borrow(cs);
            let mut state = cell.get();
            state.published = state.published.max(frame.saturating_add(1));
            cell.set(state);
        });
    }

    /// The next column, in frame order then column order.
    pub fn take(&self) -> Result<Task, Wait> {
        critical_section::with(|cs| {
            let cell = self.state.borrow(cs);
            let mut state = cell.get();
            let task = state.next;
            if task.frame >= self.frames || self.width == 0 {
                return Err(Wait::Finished);
            }
            if task.frame >= state.published {
                return Err(Wait::NotPublished { frame: task.frame });
            }
            state.next = if task.column + 1 < self.width {
                Task {
                    frame: task.frame,
                    column: task.column + 1,
                }
            } else {
                Task {
                    frame: task.frame + 1,
                    column: 0,
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
    fn every_column_of_every_frame_is_taken_once_in_order() {
        let pool = ColumnPool::new(4, 3);
        pool.publish(2);
        let mut taken = std::vec::Vec::new();
        while let Ok(task) = pool.take() {
            taken.push((task.frame, task.column));
        }
        let expected: std::vec::Vec<_> = (0..3).flat_map(|f| (0..4).map(move |c| (f, c))).collect();
        assert_eq!(taken, expected);
        assert_eq!(pool.take(), Err(Wait::Finished));
    }

    #[test]
    fn threads_share_the_pool_without_losing_or_repeating_a_column() {
        let pool = ColumnPool::new(97, 5);
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
        all.sort_by_key(|t| (t.frame, t.column));
        assert_eq!(all.len(), 97 * 5);
        for (i, task) in all.iter().enumerate() {
            assert_eq!(
                (task.frame, task.column),
                ((i / 97) as u32, (i % 97) as u32)
            );
        }
    }

    #[test]
    fn empty_pools_are_finished() {
        assert_eq!(ColumnPool::new(0, 3).take(), Err(Wait::Finished));
        let none = ColumnPool::new(5, 0);
        none.publish(0);
        assert_eq!(none.take(), Err(Wait::Finished));
    }
}
