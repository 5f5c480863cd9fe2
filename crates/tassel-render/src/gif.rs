//! Canvases as an animated GIF: one global palette of the colours the frames use (the
//! pictures are drawn without anti-aliasing, so a few dozen); beyond 256 colours, the
//! 3-3-2-bit colour cube.

use crate::canvas::Canvas;
use std::borrow::Cow;
use std::collections::HashMap;

/// Encodes `frames` (all the same size) as a looping GIF, each shown `delay_cs`
/// hundredths of a second.
pub fn encode_gif(frames: &[Canvas], delay_cs: u16) -> Result<Vec<u8>, String> {
    let first = frames.first().ok_or("a GIF needs at least one frame")?;
    let (w, h) = (first.width(), first.height());
    if frames.iter().any(|f| f.width() != w || f.height() != h) {
        return Err("GIF frames differ in size".into());
    }
    if w == 0 || h == 0 || w > u16::MAX as usize || h > u16::MAX as usize {
        return Err(format!("a GIF cannot be {w} × {h} pixels"));
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
        let mut enc =
            gif::Encoder::new(&mut out, w as u16, h as u16, &palette).map_err(|e| e.to_string())?;
        enc.set_repeat(gif::Repeat::Infinite)
            .map_err(|e| e.to_string())?;
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
            enc.write_frame(&frame).map_err(|e| e.to_string())?;
        }
    }
    Ok(out)
}
