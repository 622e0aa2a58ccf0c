//! A window of an image: the pixel rectangle that `render_window` renders
//! and that a render job's `spacing_window` spaces its instants for.

use crate::error::{Error, Result};

/// A window of the image: left column, top row, width and height, px.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Window {
    /// Left column, px.
    pub x0: u32,
    /// Top row, px.
    pub y0: u32,
    /// Width, px (at least 1).
    pub w: u32,
    /// Height, px (at least 1).
    pub h: u32,
}

impl Window {
    /// Refuses a window that is empty or not inside a `width` x `height`
    /// image, naming it as `what` (e.g. `window`).
    pub fn check(&self, what: &str, width: u32, height: u32) -> Result<()> {
        if self.w > 0
            && self.h > 0
            && u64::from(self.x0) + u64::from(self.w) <= u64::from(width)
            && u64::from(self.y0) + u64::from(self.h) <= u64::from(height)
        {
            return Ok(());
        }
        Err(Error::invalid(
            what,
            format!(
                "[{}, {}, {} x {}] is empty or outside the {width} x {height} image",
                self.x0, self.y0, self.w, self.h
            ),
        ))
    }

    /// The window's pixels cut from a whole `width`-wide interleaved RGB image.
    pub fn cut(&self, width: u32, rgb: &[f32]) -> Vec<f32> {
        let (w, x0) = (width as usize, self.x0 as usize);
        let mut out = Vec::with_capacity(self.w as usize * self.h as usize * 3);
        for y in self.y0 as usize..(self.y0 + self.h) as usize {
            out.extend_from_slice(&rgb[3 * (y * w + x0)..3 * (y * w + x0 + self.w as usize)]);
        }
        out
    }
}
