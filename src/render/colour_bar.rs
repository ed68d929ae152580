//! A colour bar drawn into a rendered picture (screenshots of data colours): the colour map as
//! a horizontal gradient in the bottom-right corner with its low and high values written above
//! its ends in a built-in 3x5 pixel font (digits, sign, point, `e`), so no font library is
//! needed. Works on the RGBA8 image after readback, so every picture path can add it.

use super::readback::RgbaImage;
use crate::model::ColourMap;

/// 3x5 glyphs, one row of 3 bits per byte (bit 2 = left), for `0-9 - . e`.
const GLYPHS: [(char, [u8; 5]); 13] = [
    ('0', [7, 5, 5, 5, 7]),
    ('1', [2, 6, 2, 2, 7]),
    ('2', [7, 1, 7, 4, 7]),
    ('3', [7, 1, 7, 1, 7]),
    ('4', [5, 5, 7, 1, 1]),
    ('5', [7, 4, 7, 1, 7]),
    ('6', [7, 4, 7, 5, 7]),
    ('7', [7, 1, 1, 1, 1]),
    ('8', [7, 5, 7, 5, 7]),
    ('9', [7, 5, 7, 1, 7]),
    ('-', [0, 0, 7, 0, 0]),
    ('.', [0, 0, 0, 0, 2]),
    ('e', [0, 7, 7, 4, 7]),
];

/// A number as the bar's label: up to 4 significant digits, no trailing zeros.
pub fn label(v: f32) -> String {
    if v != 0.0 && (v.abs() >= 1e5 || v.abs() < 1e-3) {
        return format!("{v:.2e}");
    }
    let text = format!("{v:.3}");
    let text = text.trim_end_matches('0').trim_end_matches('.');
    if text == "-0" {
        "0".into()
    } else {
        text.into()
    }
}

/// Draws the colour bar of `map` over `range` into `image` (bottom right, about a quarter of
/// its width); nothing for images smaller than 64 x 32 pixels.
pub fn draw_colour_bar(image: &mut RgbaImage, map: ColourMap, range: [f32; 2]) {
    let (w, h) = (image.width as i64, image.height as i64);
    if w < 64 || h < 32 {
        return;
    }
    let scale = (h / 240).clamp(1, 4);
    let bar_w = (w / 4).max(48);
    let bar_h = 6 * scale;
    let margin = 4 * scale;
    let x0 = w - bar_w - margin;
    let y0 = h - bar_h - margin;
    // A dark frame, then the gradient.
    fill(image, x0 - 1, y0 - 1, bar_w + 2, bar_h + 2, [0, 0, 0]);
    for x in 0..bar_w {
        let c = map.srgb8(x as f32 / (bar_w - 1).max(1) as f32);
        fill(image, x0 + x, y0, 1, bar_h, c);
    }
    let text_y = y0 - 1 - 7 * scale;
    let lo = label(range[0]);
    let hi = label(range[1]);
    text(image, x0, text_y, scale, &lo);
    let hi_w = hi.chars().count() as i64 * 4 * scale;
    text(image, x0 + bar_w - hi_w, text_y, scale, &hi);
}

/// Fills a rectangle (clipped) with an opaque sRGB colour.
fn fill(image: &mut RgbaImage, x: i64, y: i64, w: i64, h: i64, c: [u8; 3]) {
    let (iw, ih) = (image.width as i64, image.height as i64);
    for yy in y.max(0)..(y + h).min(ih) {
        for xx in x.max(0)..(x + w).min(iw) {
            let k = ((yy * iw + xx) * 4) as usize;
            image.pixels[k..k + 4].copy_from_slice(&[c[0], c[1], c[2], 255]);
        }
    }
}

/// Writes `s` in white with a dark outline, `scale` pixels per font pixel.
fn text(image: &mut RgbaImage, x: i64, y: i64, scale: i64, s: &str) {
    for pass in 0..2 {
        for (k, ch) in s.chars().enumerate() {
            let Some((_, rows)) = GLYPHS.iter().find(|(g, _)| *g == ch) else {
                continue;
            };
            for (r, bits) in rows.iter().enumerate() {
                for col in 0..3 {
                    if bits & (4 >> col) == 0 {
                        continue;
                    }
                    let px = x + (k as i64 * 4 + col) * scale;
                    let py = y + r as i64 * scale;
                    if pass == 0 {
                        fill(image, px - 1, py - 1, scale + 2, scale + 2, [0, 0, 0]);
                    } else {
                        fill(image, px, py, scale, scale, [255, 255, 255]);
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_and_bar_pixels() {
        assert_eq!(label(-1.0), "-1");
        assert_eq!(label(0.25), "0.25");
        assert_eq!(label(12.3456), "12.346");
        assert_eq!(label(2.5e-5), "2.50e-5");
        let mut img = RgbaImage {
            width: 200,
            height: 100,
            pixels: vec![40; 200 * 100 * 4],
        };
        draw_colour_bar(&mut img, ColourMap::BlueWhiteRed, [-1.0, 1.0]);
        let at = |x: usize, y: usize| {
            let k = (y * 200 + x) * 4;
            [img.pixels[k], img.pixels[k + 1], img.pixels[k + 2]]
        };
        // Bar: x 146..196, y 90..96; blue at the left end, red at the right.
        assert_eq!(at(146, 92), ColourMap::BlueWhiteRed.srgb8(0.0));
        assert_eq!(at(195, 92), ColourMap::BlueWhiteRed.srgb8(1.0));
        // The rest of the picture is untouched.
        assert_eq!(at(10, 10), [40, 40, 40]);
    }
}
