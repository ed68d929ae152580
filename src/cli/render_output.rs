//! Where `mdsurf render`'s images go: `{frame}` and `{image}` patterns, checked before any work.

use std::path::{Path, PathBuf};

use anyhow::{Result, bail};

/// `pattern` for trajectory frame `frame` and image number `image`: `{frame}` is the frame
/// index, `{frame:0N}` the frame index zero-padded to N digits, `{image}` the image number with
/// 5 digits.
fn output_path(pattern: &Path, frame: usize, image: usize) -> PathBuf {
    let mut text = pattern
        .to_string_lossy()
        .replace("{image}", &format!("{image:05}"));
    while let Some(at) = text.find("{frame") {
        let Some(close) = text[at..].find('}').map(|c| at + c) else {
            break;
        };
        let width = text[at + "{frame".len()..close]
            .strip_prefix(":0")
            .and_then(|w| w.parse::<usize>().ok())
            .unwrap_or(0);
        text.replace_range(at..=close, &format!("{frame:0width$}"));
    }
    PathBuf::from(text)
}

/// The output path of every image; fails when the name is not a PNG or two images would share
/// a file.
pub(crate) fn output_paths(pattern: &Path, frames: &[usize]) -> Result<Vec<PathBuf>> {
    let is_png = pattern
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("png"));
    if !is_png {
        bail!(
            "-o {}: render writes PNG images or a movie; give the output a .png, .mp4 or .gif name",
            pattern.display()
        );
    }
    let paths: Vec<PathBuf> = frames
        .iter()
        .enumerate()
        .map(|(i, &f)| output_path(pattern, f, i))
        .collect();
    let mut unique = paths.clone();
    unique.sort();
    unique.dedup();
    if unique.len() < paths.len() {
        let hint = if frames.windows(2).any(|w| w[0] == w[1]) {
            "{image} (the image number)"
        } else {
            "{frame} (the trajectory frame) or {image} (the image number)"
        };
        bail!(
            "{} images to write share the name {}: put {hint} in the output name, e.g. -o out/frame_{{frame:05}}.png",
            frames.len(),
            pattern.display()
        );
    }
    Ok(paths)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn patterns_name_one_file_per_image() {
        assert_eq!(
            output_path(Path::new("d/f_{frame}.png"), 7, 0),
            Path::new("d/f_7.png")
        );
        assert_eq!(
            output_path(Path::new("d/f_{frame:04}_{image}.png"), 7, 2),
            Path::new("d/f_0007_00002.png")
        );
        let jpg = output_paths(Path::new("x.jpg"), &[0])
            .unwrap_err()
            .to_string();
        assert!(jpg.contains(".png, .mp4 or .gif"), "{jpg}");
        assert!(output_paths(Path::new("x_{frame}.png"), &[3, 3]).is_err());
        assert!(output_paths(Path::new("x_{image}.png"), &[3, 3]).is_ok());
    }
}
