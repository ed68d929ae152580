//! One movie file of either kind, chosen by its name: `.mp4` (H.264, [`super::video`]) or `.gif`
//! (an animated GIF, [`super::gif_movie`]). `render -o`, the window's movie export and
//! `mdsurf merge` go through [`Movie`] and [`MovieFormat`]; both kinds are written atomically.

use std::path::Path;

use super::gif_movie::{GifMovie, check_gif_fps, check_gif_size};
use super::video::{MovieSummary, Mp4Movie, VideoError, VideoQuality, check_even_size, check_fps};
use crate::render::RgbaImage;

/// The movie formats written, by file extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MovieFormat {
    /// H.264 in MP4 (`.mp4`).
    Mp4,
    /// Animated GIF (`.gif`).
    Gif,
}

impl MovieFormat {
    /// The format `path` names (extension in any case), or `None` for anything else.
    pub fn of(path: &Path) -> Option<MovieFormat> {
        let ext = path.extension()?.to_str()?;
        if ext.eq_ignore_ascii_case("mp4") {
            Some(MovieFormat::Mp4)
        } else if ext.eq_ignore_ascii_case("gif") {
            Some(MovieFormat::Gif)
        } else {
            None
        }
    }

    /// Checks a picture size and frame rate for this format before any work: H.264 needs even
    /// sides, a GIF at most 65,535 pixels a side and 50 frames per second.
    pub fn check(self, path: &Path, size: [u32; 2], fps: f64) -> Result<(), VideoError> {
        match self {
            MovieFormat::Mp4 => {
                check_even_size(path, size)?;
                check_fps(fps).map_err(|e| VideoError::Codec {
                    path: path.to_path_buf(),
                    what: "frame rate",
                    message: e.to_string(),
                })?;
            }
            MovieFormat::Gif => {
                check_gif_size(path, size)?;
                check_gif_fps(path, fps)?;
            }
        }
        Ok(())
    }
}

/// Whether `path` names a movie file (`.mp4` or `.gif`).
pub fn is_movie(path: &Path) -> bool {
    MovieFormat::of(path).is_some()
}

/// A movie being written; dropped without [`Movie::finish`], it leaves no file.
pub enum Movie {
    /// An H.264 MP4 movie (boxed, as the GIF: each writer's state is some kilobytes).
    Mp4(Box<Mp4Movie>),
    /// An animated GIF.
    Gif(Box<GifMovie>),
}

impl Movie {
    /// Starts the movie `path` names (see [`MovieFormat::of`]; anything else is written as MP4)
    /// of `size` pixels at `fps` frames per second, whose first image is image `first_frame` of
    /// the whole movie (a chunk's part starts later; it sets a GIF's first delays).
    pub fn create(
        path: &Path,
        size: [u32; 2],
        fps: f64,
        quality: VideoQuality,
        first_frame: usize,
    ) -> Result<Movie, VideoError> {
        Ok(match MovieFormat::of(path) {
            Some(MovieFormat::Gif) => Movie::Gif(Box::new(GifMovie::create(
                path,
                size,
                fps,
                quality,
                first_frame,
            )?)),
            _ => Movie::Mp4(Box::new(Mp4Movie::create(path, size, fps, quality)?)),
        })
    }

    /// The output path.
    pub fn path(&self) -> &Path {
        match self {
            Movie::Mp4(m) => m.path(),
            Movie::Gif(m) => m.path(),
        }
    }

    /// Images added so far.
    pub fn frames(&self) -> usize {
        match self {
            Movie::Mp4(m) => m.frames(),
            Movie::Gif(m) => m.frames(),
        }
    }

    /// Adds `image` as the next frame.
    pub fn push(&mut self, image: &RgbaImage) -> Result<(), VideoError> {
        match self {
            Movie::Mp4(m) => m.push(image),
            Movie::Gif(m) => m.push(image),
        }
    }

    /// Finishes the file and renames it into place.
    pub fn finish(self) -> Result<MovieSummary, VideoError> {
        match self {
            Movie::Mp4(m) => m.finish(),
            Movie::Gif(m) => m.finish(),
        }
    }
}
