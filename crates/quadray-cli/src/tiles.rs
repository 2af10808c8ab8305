//! Splitting one frame into pieces rendered by separate processes (`render --tile I/N`), and what
//! a piece records so that `merge` can check the pieces belong together.
//!
//! # Layout
//! The frame's rows are cut into `8·N` bands (fewer when the image has fewer rows), and piece `I`
//! takes every band whose index is `I` modulo `N`: bands 0, N, 2N, … for piece 0. Interleaving
//! balances the work: the cost of a row depends on what it shows (sky is cheap, mirrors are
//! dear, and they sit in different parts of a frame), so contiguous slices leave the piece that
//! drew the expensive part running long after the others, while interleaved bands give every
//! piece a sample of each part of the frame. Bands stay whole rows, so each is one rectangle: one
//! part of the piece's EXR file, its data window placed in the full display window.

use quadray::PixelWindow;

/// Bands per piece: enough to sample the frame's regions evenly, few enough that each band is a
/// useful amount of work (on a 1080-row frame split 16 ways, bands of 8 or 9 rows).
const BANDS_PER_PIECE: u32 = 8;

/// Which piece of how many (`--tile I/N`, `I` counted from 0).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Piece {
    /// This piece's index, `0..count`.
    pub index: u32,
    /// How many pieces the frame is cut into.
    pub count: u32,
}

impl std::fmt::Display for Piece {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

/// Parses `I/N` with `0 <= I < N`.
pub fn parse_piece(s: &str) -> Result<Piece, String> {
    let bad = || format!("expected I/N with 0 <= I < N (e.g. 3/16), got \"{s}\"");
    let (i, n) = s.split_once('/').ok_or_else(bad)?;
    let (index, count) = (
        i.trim().parse::<u32>().map_err(|_| bad())?,
        n.trim().parse::<u32>().map_err(|_| bad())?,
    );
    if index >= count {
        return Err(bad());
    }
    Ok(Piece { index, count })
}

/// How many row bands a `height`-row frame in `count` pieces is cut into.
pub fn band_count(height: u32, count: u32) -> u32 {
    count.saturating_mul(BANDS_PER_PIECE).min(height)
}

/// The bands of rows piece `piece` renders in a `width` × `height` frame, top to bottom; empty
/// when the frame has fewer rows than pieces (the caller refuses that).
pub fn piece_bands(piece: Piece, width: u32, height: u32) -> Vec<PixelWindow> {
    let bands = band_count(height, piece.count);
    // Band j covers rows [j·h/B, (j+1)·h/B): exact integer edges, so the bands tile the frame.
    let edge = |j: u32| (j as u64 * height as u64 / bands.max(1) as u64) as u32;
    (piece.index..bands)
        .step_by(piece.count as usize)
        .map(|j| PixelWindow {
            x0: 0,
            y0: edge(j),
            x1: width,
            y1: edge(j + 1),
        })
        .collect()
}

/// A 64-bit FNV-1a hash, written out in hex: stable across platforms and versions, so pieces
/// rendered on different machines can be compared (it identifies, it does not protect).
pub fn fnv1a_hex(parts: &[&[u8]]) -> String {
    let mut hash = FNV_OFFSET;
    for part in parts {
        // Each part's length first, so ("ab", "c") and ("a", "bc") differ.
        hash = fnv1a(hash, &(part.len() as u64).to_le_bytes());
        hash = fnv1a(hash, part);
    }
    format!("{hash:016x}")
}

/// [`fnv1a_hex`] of one part, the contents of the file at `path`, read a block at a time (a
/// mesh may be gigabytes).
pub fn fnv1a_file_hex(path: &std::path::Path) -> std::io::Result<String> {
    use std::io::Read;
    let mut file = std::fs::File::open(path)?;
    let length = file.metadata()?.len();
    let mut hash = fnv1a(FNV_OFFSET, &length.to_le_bytes());
    let mut block = vec![0u8; 1 << 20];
    loop {
        let n = file.read(&mut block)?;
        if n == 0 {
            break;
        }
        hash = fnv1a(hash, &block[..n]);
    }
    Ok(format!("{hash:016x}"))
}

/// FNV-1a's starting value.
const FNV_OFFSET: u64 = 0xcbf2_9ce4_8422_2325;

/// FNV-1a's step over `bytes` from `hash`.
fn fnv1a(mut hash: u64, bytes: &[u8]) -> u64 {
    for &byte in bytes {
        hash ^= byte as u64;
        hash = hash.wrapping_mul(0x0100_0000_01b3);
    }
    hash
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pieces_parse_and_refuse_nonsense() {
        assert_eq!(
            parse_piece("3/16"),
            Ok(Piece {
                index: 3,
                count: 16
            })
        );
        for bad in ["16/16", "1", "a/2", "-1/2", "1/0", "0/0"] {
            assert!(parse_piece(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn the_pieces_bands_cover_every_row_once() {
        for (height, count) in [(1080, 16), (45, 7), (7, 7), (10, 3), (1, 1)] {
            let mut covered = vec![0u32; height as usize];
            for index in 0..count {
                let bands = piece_bands(Piece { index, count }, 5, height);
                assert!(!bands.is_empty(), "{height} rows, piece {index}/{count}");
                for b in bands {
                    assert!(b.height() > 0 && b.width() == 5);
                    for y in b.y0..b.y1 {
                        covered[y as usize] += 1;
                    }
                }
            }
            assert!(covered.iter().all(|&c| c == 1), "{height} rows in {count}");
        }
        // Interleaved: piece 0 of 2 takes bands 0, 2, 4, …
        let bands = piece_bands(Piece { index: 0, count: 2 }, 4, 160);
        assert_eq!(bands.len(), 8);
        assert_eq!((bands[0].y0, bands[0].y1, bands[1].y0), (0, 10, 20));
    }

    #[test]
    fn hashes_are_stable_and_separate_their_parts() {
        assert_eq!(fnv1a_hex(&[]), "cbf29ce484222325");
        assert_ne!(fnv1a_hex(&[b"ab", b"c"]), fnv1a_hex(&[b"a", b"bc"]));
        assert_eq!(fnv1a_hex(&[b"scene"]), fnv1a_hex(&[b"scene"]));
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("mesh.obj");
        let bytes: Vec<u8> = (0..3_000_000u32).map(|i| (i % 251) as u8).collect();
        std::fs::write(&path, &bytes).unwrap();
        assert_eq!(fnv1a_file_hex(&path).unwrap(), fnv1a_hex(&[&bytes]));
    }
}
