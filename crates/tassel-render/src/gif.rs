//! Canvases as an animated GIF: one global palette of the colours the frames use (the
//! pictures are drawn without anti-aliasing, so a few dozen); beyond 256 colours, the
//! 3-3-2-bit colour cube.

use crate::canvas::Canvas;
use crate::error::RenderError;
use std::borrow::Cow;
use std::collections::HashMap;

/// Encodes `frames` (all the same size) as a looping GIF, each shown `delay_cs`
/// hundredths of a second.
pub fn encode_gif(frames: &[Canvas], delay_cs: u16) -> Result<Vec<u8>, RenderError> {
    let bad = |m: String| RenderError::Gif(m);
    let first = frames
        .first()
        .ok_or_else(|| bad("a GIF needs at least one frame".into()))?;
    let (w, h) = (first.width(), first.height());
    if frames.iter().any(|f| f.width() != w || f.height() != h) {
        return Err(bad("GIF frames differ in size".into()));
    }
    if w == 0 || h == 0 || w > u16::MAX as usize || h > u16::MAX as usize {
        return Err(bad(format!("a GIF cannot be {w} × {h} pixels")));
    }
    let mut index: HashMap<[u8; 3], u8> = HashMap::new();
    let mut palette: Vec<u8> = Vec::new();
    let mut exact = true;
    'scan: for f in frames {
        for px in f.pixels().chunks_exact(3) {
            let c = [px[0], px[1], px[2]];
            if !index.contains_key(&c) {
                if index.len() == 256 {
                    exact = false;
                    break 'scan;
                }
                index.insert(c, index.len() as u8);
                palette.extend(c);
            }
        }
    }
    if !exact {
        palette.clear();
        for i in 0..=255u8 {
            palette.extend([
                (i >> 5) * 255 / 7,
                ((i >> 2) & 7) * 255 / 7,
                (i & 3) * 255 / 3,
            ]);
        }
    }
    let mut out = Vec::new();
    {
        let mut enc = gif::Encoder::new(&mut out, w as u16, h as u16, &palette)
            .map_err(|e| bad(e.to_string()))?;
        enc.set_repeat(gif::Repeat::Infinite)
            .map_err(|e| bad(e.to_string()))?;
        for f in frames {
            let buffer: Vec<u8> = f
                .pixels()
                .chunks_exact(3)
                .map(|p| {
                    if exact {
                        index[&[p[0], p[1], p[2]]]
                    } else {
                        (p[0] >> 5) << 5 | (p[1] >> 5) << 2 | p[2] >> 6
                    }
                })
                .collect();
            let frame = gif::Frame {
                width: w as u16,
                height: h as u16,
                delay: delay_cs,
                buffer: Cow::Owned(buffer),
                ..gif::Frame::default()
            };
            enc.write_frame(&frame).map_err(|e| bad(e.to_string()))?;
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Bad frame lists are typed errors naming the problem, not panics.
    #[test]
    fn bad_frames_are_gif_errors() {
        let is_gif_error = |r: Result<Vec<u8>, RenderError>, word: &str| matches!(r, Err(RenderError::Gif(m)) if m.contains(word));
        assert!(is_gif_error(encode_gif(&[], 5), "at least one frame"));
        let frames = [Canvas::new(4, 3, [255; 3]), Canvas::new(3, 4, [255; 3])];
        assert!(is_gif_error(encode_gif(&frames, 5), "differ in size"));
        // Two equal frames make a GIF: the header's magic and size by hand.
        let ok = encode_gif(
            &[Canvas::new(4, 3, [255; 3]), Canvas::new(4, 3, [255; 3])],
            5,
        )
        .unwrap();
        assert_eq!(&ok[..6], b"GIF89a");
        assert_eq!(u16::from_le_bytes([ok[6], ok[7]]), 4);
        assert_eq!(u16::from_le_bytes([ok[8], ok[9]]), 3);
    }
}
