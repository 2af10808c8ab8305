//! `quadray merge`: assembles the pieces of a frame rendered by `render --tile I/N` into the
//! image one process would have written, after checking that they belong together.

use crate::exr_file::{ExrCamera, ExrFrame, film_and_aovs, read_exr, write_exr};
use crate::output::{Format, check_writable, write_film};
use crate::render_cmd::PIECE;
use crate::tiles::{Piece, parse_piece, piece_bands};
use anyhow::{Context, Result, bail};
use clap::Args;
use exr::prelude::FlatSamples;
use quadray::PixelWindow;
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

/// Arguments of `quadray merge`.
#[derive(Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct MergeArgs {
    /// The pieces (`render --tile I/N` outputs), in any order.
    #[arg(required = true, value_name = "PIECE.exr")]
    pub pieces: Vec<PathBuf>,
    /// The merged image: .exr keeps every pass, .png shows the beauty image.
    #[arg(short, long, value_name = "OUT", value_parser = crate::args::parse_image_output,
          required_unless_present = "missing")]
    pub output: Option<PathBuf>,
    /// Print the indices of the pieces still to render, one per line, and merge nothing.
    #[arg(long)]
    pub missing: bool,
    /// Print nothing but errors.
    #[arg(short, long)]
    pub quiet: bool,
}

/// One piece as read: which it is, what it came from, and its rectangles' channels.
struct ReadPiece {
    path: PathBuf,
    piece: Piece,
    scene: String,
    settings: String,
    size: (u32, u32),
    parts: Vec<(PixelWindow, Vec<(String, FlatSamples)>)>,
    /// The camera the piece was rendered through (every piece of a frame has the same).
    camera: Option<ExrCamera>,
}

impl ReadPiece {
    /// The channel names and sample types of its first rectangle.
    fn channels(&self) -> Vec<String> {
        self.parts[0]
            .1
            .iter()
            .map(|(name, samples)| {
                let kind = if matches!(samples, FlatSamples::F16(_)) {
                    "half"
                } else {
                    "float"
                };
                format!("{name} ({kind})")
            })
            .collect()
    }
}

/// Runs the merge subcommand.
pub fn run(args: &MergeArgs) -> Result<()> {
    let format = args.output.as_deref().map(check_writable).transpose()?;
    if let Some(output) = &args.output {
        // The merge would replace a piece that a retry still needs.
        crate::overwrite::refuse_replacing_an_input(
            "-o",
            output,
            &args.pieces,
            "one of the pieces to merge",
        )?;
    }
    let pieces = args
        .pieces
        .iter()
        .map(|p| read_piece(p))
        .collect::<Result<Vec<_>>>()?;
    let count = check_together(&pieces)?;
    let mut by_index: BTreeMap<u32, Vec<&Path>> = BTreeMap::new();
    for p in &pieces {
        by_index.entry(p.piece.index).or_default().push(&p.path);
    }
    let missing: Vec<u32> = (0..count).filter(|i| !by_index.contains_key(i)).collect();
    if args.missing {
        for i in missing {
            outln!("{i}")?;
        }
        return Ok(());
    }
    let mut problems: Vec<String> = by_index
        .iter()
        .filter(|(_, paths)| paths.len() > 1)
        .map(|(i, paths)| {
            let names: Vec<String> = paths.iter().map(|p| p.display().to_string()).collect();
            format!(
                "piece {i}/{count} is given {} times: {}",
                paths.len(),
                names.join(", ")
            )
        })
        .collect();
    if !missing.is_empty() {
        let list: Vec<String> = missing.iter().map(u32::to_string).collect();
        problems.push(format!(
            "pieces missing: {} (of {count}, numbered from 0; render each with --tile I/{count}, \
             and `merge --missing` lists them)",
            list.join(", ")
        ));
    }
    if !problems.is_empty() {
        bail!("the pieces do not make one frame: {}", problems.join("; "));
    }
    let (Some(output), Some(format)) = (&args.output, format) else {
        bail!("merge needs -o OUT.exr or OUT.png (or --missing)");
    };
    let (width, height) = pieces[0].size;
    let channels = assemble(&pieces, (width, height))?;
    let (film, aovs, half) = film_and_aovs((width, height), &channels)?;
    match format {
        Format::Exr => {
            let frame = ExrFrame {
                camera: pieces[0].camera,
                ..ExrFrame::full(width, height)
            };
            write_exr(&film, aovs.as_ref(), half, &frame, output)?;
        }
        Format::Png => write_film(&film, output)?,
    }
    if !args.quiet {
        errln!(
            "{width}x{height} from {} -> {}",
            crate::counted(count, "piece"),
            output.display()
        );
    }
    Ok(())
}

/// Reads a piece and the attributes `render --tile` wrote into it.
fn read_piece(path: &Path) -> Result<ReadPiece> {
    let read = read_exr(path)?;
    let Some(value) = read.attributes.get(PIECE) else {
        bail!(
            "{}: not a piece of a quadray render (no {PIECE} attribute; pieces come from \
             `quadray render --tile I/N`)",
            path.display()
        );
    };
    let (piece, scene, settings) = parse_piece_attribute(value)
        .map_err(|e| anyhow::anyhow!("{}: {PIECE}: {e}", path.display()))?;
    if read.parts.is_empty() {
        bail!("{}: the file holds no pixels", path.display());
    }
    quadray::render::check_resolution(read.size.0, read.size.1)
        .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    Ok(ReadPiece {
        path: path.to_path_buf(),
        piece,
        scene,
        settings,
        size: read.size,
        parts: read.parts,
        camera: read.camera,
    })
}

/// The piece, scene hash and settings of a [`PIECE`] attribute.
fn parse_piece_attribute(value: &str) -> Result<(Piece, String, String)> {
    let mut lines = value.lines();
    let piece = parse_piece(lines.next().unwrap_or_default()).map_err(anyhow::Error::msg)?;
    let mut field = |key: &str| {
        lines
            .next()
            .and_then(|line| line.strip_prefix(key))
            .map(str::to_string)
            .with_context(|| format!("no `{key}` line in {value:?}"))
    };
    Ok((piece, field("scene: ")?, field("settings: ")?))
}

/// Checks that every piece comes from the same scene and settings, cuts the frame the same way,
/// holds the same passes and exactly its own rows; returns the piece count.
fn check_together(pieces: &[ReadPiece]) -> Result<u32> {
    let first = &pieces[0];
    let mut problems = Vec::new();
    for p in pieces {
        let name = p.path.display();
        if p.scene != first.scene {
            problems.push(format!(
                "{name} was rendered from another scene than {} (scene hash {} against {})",
                first.path.display(),
                p.scene,
                first.scene
            ));
        }
        if p.settings != first.settings {
            problems.push(format!(
                "{name} was rendered with other settings than {} ({} against {})",
                first.path.display(),
                p.settings,
                first.settings
            ));
        }
        if p.piece.count != first.piece.count {
            problems.push(format!(
                "{name} is piece {} of a frame cut into {} pieces, {} of one cut into {}",
                p.piece,
                p.piece.count,
                first.path.display(),
                first.piece.count
            ));
        }
        if p.channels() != first.channels()
            || p.parts.iter().any(|(_, c)| c.len() != p.parts[0].1.len())
        {
            problems.push(format!(
                "{name} holds other passes ({}) than {} ({})",
                p.channels().join(", "),
                first.path.display(),
                first.channels().join(", ")
            ));
        }
        let (w, h) = p.size;
        let expected = piece_bands(p.piece, w, h);
        let rows: Vec<PixelWindow> = p.parts.iter().map(|(window, _)| *window).collect();
        if p.size == first.size && rows != expected {
            problems.push(format!(
                "{name} does not hold the rows of piece {} (its parts overlap other pieces or \
                 leave rows out)",
                p.piece
            ));
        }
    }
    if !problems.is_empty() {
        bail!("the pieces do not make one frame: {}", problems.join("; "));
    }
    Ok(first.piece.count)
}

/// Copies every piece's rectangles into full-frame channels by name.
fn assemble(
    pieces: &[ReadPiece],
    (width, height): (u32, u32),
) -> Result<HashMap<String, FlatSamples>> {
    let n = width as usize * height as usize;
    let mut channels: HashMap<String, FlatSamples> = HashMap::new();
    for (name, samples) in &pieces[0].parts[0].1 {
        let empty = match samples {
            FlatSamples::F16(_) => FlatSamples::F16(vec![Default::default(); n]),
            FlatSamples::F32(_) => FlatSamples::F32(vec![0.0; n]),
            FlatSamples::U32(_) => FlatSamples::U32(vec![0; n]),
        };
        channels.insert(name.clone(), empty);
    }
    for piece in pieces {
        for (window, parts) in &piece.parts {
            let w = window.width() as usize;
            for (name, samples) in parts {
                let target = channels
                    .get_mut(name)
                    .context("a channel the first piece lacks")?;
                for row in 0..window.height() as usize {
                    let at = (window.y0 as usize + row) * width as usize + window.x0 as usize;
                    let from = row * w..(row + 1) * w;
                    match (&mut *target, samples) {
                        (FlatSamples::F16(t), FlatSamples::F16(s)) => {
                            t[at..at + w].copy_from_slice(&s[from])
                        }
                        (FlatSamples::F32(t), FlatSamples::F32(s)) => {
                            t[at..at + w].copy_from_slice(&s[from])
                        }
                        (FlatSamples::U32(t), FlatSamples::U32(s)) => {
                            t[at..at + w].copy_from_slice(&s[from])
                        }
                        _ => bail!("{}: channel {name} changes type", piece.path.display()),
                    }
                }
            }
        }
    }
    Ok(channels)
}
