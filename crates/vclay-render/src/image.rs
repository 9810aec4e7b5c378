//! RGB images and their encoding: PNG (one picture, or numbered PNGs) and animated GIF.

use crate::error::RenderError;
use std::path::{Path, PathBuf};

/// An 8-bit RGB image, rows top to bottom.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width * height * 3` bytes, row-major, RGB.
    pub data: Vec<u8>,
}

fn encode_err(path: &Path, format: &'static str, e: impl std::fmt::Display) -> RenderError {
    RenderError::Encode {
        path: path.to_path_buf(),
        format,
        message: e.to_string(),
    }
}

impl Image {
    /// An image filled with one colour.
    pub fn filled(width: u32, height: u32, color: [u8; 3]) -> Image {
        let n = width as usize * height as usize;
        Image {
            width,
            height,
            data: color.iter().copied().cycle().take(3 * n).collect(),
        }
    }

    /// The colour at `(x, y)` (`x` to the right, `y` down).
    ///
    /// # Panics
    /// When `(x, y)` is outside the image.
    #[track_caller]
    pub fn pixel(&self, x: u32, y: u32) -> [u8; 3] {
        assert!(
            x < self.width && y < self.height,
            "pixel ({x}, {y}) outside"
        );
        let i = 3 * (y as usize * self.width as usize + x as usize);
        [self.data[i], self.data[i + 1], self.data[i + 2]]
    }

    /// PNG bytes of the image.
    pub fn encode_png(&self) -> Result<Vec<u8>, RenderError> {
        let mut out = Vec::new();
        self.write_png_to(&mut out, Path::new("<memory>"))?;
        Ok(out)
    }

    fn write_png_to(&self, w: &mut dyn std::io::Write, path: &Path) -> Result<(), RenderError> {
        let mut enc = png::Encoder::new(w, self.width, self.height);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_compression(png::Compression::Fast);
        let mut writer = enc.write_header().map_err(|e| encode_err(path, "PNG", e))?;
        writer
            .write_image_data(&self.data)
            .map_err(|e| encode_err(path, "PNG", e))?;
        writer.finish().map_err(|e| encode_err(path, "PNG", e))
    }

    /// Writes the image as PNG, atomically (temporary file renamed over `path`).
    pub fn write_png(&self, path: impl AsRef<Path>) -> Result<(), RenderError> {
        let bytes = self.encode_png()?;
        vclay_io::write_atomic(path.as_ref(), |w| w.write_all(&bytes))?;
        Ok(())
    }

    /// Decodes 8-bit RGB or RGBA PNG bytes (alpha is dropped); used to read pictures back.
    pub fn decode_png(bytes: &[u8]) -> Result<Image, RenderError> {
        let path = Path::new("<memory>");
        let dec = png::Decoder::new(std::io::Cursor::new(bytes));
        let mut reader = dec.read_info().map_err(|e| encode_err(path, "PNG", e))?;
        let size = reader
            .output_buffer_size()
            .ok_or_else(|| encode_err(path, "PNG", "image too large"))?;
        let mut buf = vec![0; size];
        let info = reader
            .next_frame(&mut buf)
            .map_err(|e| encode_err(path, "PNG", e))?;
        if info.bit_depth != png::BitDepth::Eight {
            return Err(encode_err(path, "PNG", "only 8-bit images are read"));
        }
        let channels = match info.color_type {
            png::ColorType::Rgb => 3,
            png::ColorType::Rgba => 4,
            other => {
                return Err(encode_err(
                    path,
                    "PNG",
                    format!("unsupported colour type {other:?}"),
                ));
            }
        };
        let data = buf[..info.buffer_size()]
            .chunks_exact(channels)
            .flat_map(|c| [c[0], c[1], c[2]])
            .collect();
        Ok(Image {
            width: info.width,
            height: info.height,
            data,
        })
    }
}

/// Encodes frames as an endlessly looping animated GIF, `delay_ms` per frame (rounded to
/// hundredths of a second). Colours are quantized per frame (NeuQuant).
pub fn encode_gif(frames: &[Image], delay_ms: u32) -> Result<Vec<u8>, RenderError> {
    let path = Path::new("<memory>");
    let Some(first) = frames.first() else {
        return Err(RenderError::Animation("no frames".into()));
    };
    if let Some(k) = frames
        .iter()
        .position(|f| (f.width, f.height) != (first.width, first.height))
    {
        return Err(RenderError::Animation(format!(
            "frame {k} is {}x{}, frame 0 is {}x{}",
            frames[k].width, frames[k].height, first.width, first.height
        )));
    }
    let (w, h) = (first.width, first.height);
    if w > u16::MAX as u32 || h > u16::MAX as u32 {
        return Err(RenderError::Animation(format!(
            "{w}x{h} is too large for GIF"
        )));
    }
    let mut out = Vec::new();
    {
        let mut enc = gif::Encoder::new(&mut out, w as u16, h as u16, &[])
            .map_err(|e| encode_err(path, "GIF", e))?;
        enc.set_repeat(gif::Repeat::Infinite)
            .map_err(|e| encode_err(path, "GIF", e))?;
        for f in frames {
            // Speed 10: quick quantization, good enough for shaded pictures.
            let mut frame = gif::Frame::from_rgb_speed(w as u16, h as u16, &f.data, 10);
            frame.delay = (delay_ms / 10).clamp(1, u16::MAX as u32) as u16;
            enc.write_frame(&frame)
                .map_err(|e| encode_err(path, "GIF", e))?;
        }
    }
    Ok(out)
}

/// Writes frames as an animated GIF, atomically.
pub fn write_gif(
    path: impl AsRef<Path>,
    frames: &[Image],
    delay_ms: u32,
) -> Result<(), RenderError> {
    let bytes = encode_gif(frames, delay_ms).map_err(|e| match e {
        RenderError::Encode {
            format, message, ..
        } => RenderError::Encode {
            path: path.as_ref().to_path_buf(),
            format,
            message,
        },
        e => e,
    })?;
    vclay_io::write_atomic(path.as_ref(), |w| w.write_all(&bytes))?;
    Ok(())
}

/// Writes frames as numbered PNGs `dir/stem_0000.png`, `dir/stem_0001.png`, ...; returns the paths.
pub fn write_png_sequence(
    dir: impl AsRef<Path>,
    stem: &str,
    frames: &[Image],
) -> Result<Vec<PathBuf>, RenderError> {
    frames
        .iter()
        .enumerate()
        .map(|(k, f)| {
            let p = dir.as_ref().join(format!("{stem}_{k:04}.png"));
            f.write_png(&p)?;
            Ok(p)
        })
        .collect()
}
