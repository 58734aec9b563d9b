//! Heightmap files: 8- or 16-bit greyscale PNG images and CSV grids of
//! numbers, read into [`HeightField`](quadsim_engine::terrain::HeightField)
//! sample order and written by `quadsim terrain export`.
//!
//! Orientation, the same for both formats: a file is a map seen from above
//! with +x to the right and +y up. Column `c` (0-based, left to right) is the
//! x index `i = c`; row `r` (0-based, top to bottom: the first image row or
//! the first CSV line) is the y index `j = ny − 1 − r`, so the first row holds
//! the *largest* y.
//!
//! Values: a PNG sample `v` reads as the fraction `v / (2^bits − 1)` (0 to 1)
//! of the terrain's `vertical_scale_m`; a CSV number reads as itself, a
//! multiple of `vertical_scale_m` (CSV files written in metres are read with
//! `vertical_scale_m = 1`). Negative CSV numbers are allowed; PNG samples
//! cannot be negative, so an exporter stores an offset in the terrain's origin.
//!
//! Sizes: at least 2 × 2 and at most [`MAX_SAMPLES_PER_AXIS`] samples along
//! each axis; the size is checked from the PNG header, or row by row while a
//! CSV file streams, before the grid is allocated.

use std::fs::File;
use std::io::{BufReader, BufWriter, Write};
use std::path::{Path, PathBuf};

use thiserror::Error;

/// Largest number of samples along either axis of a heightmap file.
pub const MAX_SAMPLES_PER_AXIS: usize = 16_384;

/// A grid read from a heightmap file.
#[derive(Debug, Clone, PartialEq)]
pub struct HeightGrid {
    /// Samples along x (file columns).
    pub nx: usize,
    /// Samples along y (file rows).
    pub ny: usize,
    /// Samples in units of the vertical scale (PNG: `v / (2^bits − 1)`; CSV:
    /// the numbers), row-major by *increasing* y: `values[j nx + i]`.
    pub values: Vec<f64>,
}

/// What is wrong with a heightmap file; every variant names the file.
#[derive(Debug, Error)]
pub enum HeightmapError {
    /// The file cannot be opened or read.
    #[error("cannot read heightmap {}: {source}", path.display())]
    Io {
        /// The file (as resolved).
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// The file has no bytes, or a CSV file has no numbers.
    #[error("heightmap {} is empty", path.display())]
    Empty {
        /// The file.
        path: PathBuf,
    },
    /// Neither `.png` nor `.csv`.
    #[error("heightmap {}: unknown file type (expected a .png image or a .csv grid)", path.display())]
    UnknownFormat {
        /// The file.
        path: PathBuf,
    },
    /// A `.png` file that does not decode.
    #[error("heightmap {} is not a PNG image: {reason}", path.display())]
    NotPng {
        /// The file.
        path: PathBuf,
        /// The decoder's message.
        reason: String,
    },
    /// A PNG that is not 8- or 16-bit greyscale.
    #[error(
        "heightmap {}: {color} PNG with {bits}-bit samples is not supported (save it as 8- or 16-bit greyscale)",
        path.display()
    )]
    UnsupportedPng {
        /// The file.
        path: PathBuf,
        /// Its colour type.
        color: String,
        /// Its bit depth.
        bits: u8,
    },
    /// A CSV field that is not a finite number.
    #[error("heightmap {}: row {row}, column {column}: '{text}' is not a finite number", path.display())]
    NotANumber {
        /// The file.
        path: PathBuf,
        /// 1-based line of the file.
        row: u64,
        /// 1-based field of the row.
        column: usize,
        /// The field.
        text: String,
    },
    /// A CSV row whose length differs from the first row's.
    #[error(
        "heightmap {}: row {row} has {got} columns but the first row has {expected} (the grid must be rectangular)",
        path.display()
    )]
    Ragged {
        /// The file.
        path: PathBuf,
        /// 1-based line of the file.
        row: u64,
        /// Columns of the first row.
        expected: usize,
        /// Columns of this row.
        got: usize,
    },
    /// A CSV file that does not parse as CSV (e.g. an unterminated quote).
    #[error("heightmap {}: not a CSV grid: {reason}", path.display())]
    NotCsv {
        /// The file.
        path: PathBuf,
        /// The parser's message.
        reason: String,
    },
    /// More than [`MAX_SAMPLES_PER_AXIS`] samples along an axis.
    #[error(
        "heightmap {}: {nx} × {ny} samples is too large (at most {MAX_SAMPLES_PER_AXIS} × {MAX_SAMPLES_PER_AXIS})",
        path.display()
    )]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// Samples along x (columns; for a CSV file, as far as read).
        nx: usize,
        /// Samples along y (rows; for a CSV file, as far as read).
        ny: usize,
    },
    /// Fewer than 2 samples along an axis.
    #[error("heightmap {}: {nx} × {ny} samples; a heightmap needs at least 2 × 2", path.display())]
    TooSmall {
        /// The file.
        path: PathBuf,
        /// Samples along x.
        nx: usize,
        /// Samples along y.
        ny: usize,
    },
    /// Writing failed.
    #[error("cannot write heightmap {}: {reason}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// The cause.
        reason: String,
    },
}

/// File types by extension (case-insensitive).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HeightmapFormat {
    /// Greyscale PNG.
    Png,
    /// Comma-separated numbers.
    Csv,
}

impl HeightmapFormat {
    /// The format of `path` from its extension.
    pub fn of(path: &Path) -> Option<HeightmapFormat> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "png" => Some(HeightmapFormat::Png),
            "csv" => Some(HeightmapFormat::Csv),
            _ => None,
        }
    }
}

/// Reads a heightmap file (see the module docs for orientation and values).
pub fn read_heightmap(path: &Path) -> Result<HeightGrid, HeightmapError> {
    let io = |source| HeightmapError::Io {
        path: path.to_path_buf(),
        source,
    };
    let meta = std::fs::metadata(path).map_err(io)?;
    if meta.is_dir() {
        return Err(io(std::io::Error::other("is a directory")));
    }
    let format = HeightmapFormat::of(path).ok_or_else(|| HeightmapError::UnknownFormat {
        path: path.to_path_buf(),
    })?;
    if meta.len() == 0 {
        return Err(HeightmapError::Empty {
            path: path.to_path_buf(),
        });
    }
    if meta.len() > crate::limits::MAX_HEIGHTMAP_FILE_BYTES {
        return Err(io(std::io::Error::other(format!(
            "{} bytes is larger than the {} MiB a heightmap file may be",
            meta.len(),
            crate::limits::MAX_HEIGHTMAP_FILE_BYTES >> 20
        ))));
    }
    let file = File::open(path).map_err(io)?;
    let grid = match format {
        HeightmapFormat::Png => read_png(path, BufReader::new(file))?,
        HeightmapFormat::Csv => read_csv(path, BufReader::new(file))?,
    };
    if grid.nx < 2 || grid.ny < 2 {
        return Err(HeightmapError::TooSmall {
            path: path.to_path_buf(),
            nx: grid.nx,
            ny: grid.ny,
        });
    }
    Ok(grid)
}

fn check_size(path: &Path, nx: usize, ny: usize) -> Result<(), HeightmapError> {
    if nx > MAX_SAMPLES_PER_AXIS || ny > MAX_SAMPLES_PER_AXIS {
        return Err(HeightmapError::TooLarge {
            path: path.to_path_buf(),
            nx,
            ny,
        });
    }
    Ok(())
}

fn read_png(path: &Path, r: BufReader<File>) -> Result<HeightGrid, HeightmapError> {
    let not_png = |e: png::DecodingError| HeightmapError::NotPng {
        path: path.to_path_buf(),
        reason: e.to_string(),
    };
    // Room for the largest accepted image (16-bit samples); the size itself is
    // checked from the header below, before the pixel buffer exists.
    let limits = png::Limits {
        bytes: 2 * MAX_SAMPLES_PER_AXIS * MAX_SAMPLES_PER_AXIS + (1 << 24),
    };
    let mut decoder = png::Decoder::new_with_limits(r, limits);
    decoder.set_transformations(png::Transformations::IDENTITY);
    let mut reader = decoder.read_info().map_err(not_png)?;
    let (w, h) = reader.info().size();
    let (nx, ny) = (w as usize, h as usize);
    check_size(path, nx, ny)?;
    let (color, depth) = (reader.info().color_type, reader.info().bit_depth);
    let bits = depth as u8;
    if color != png::ColorType::Grayscale || !matches!(bits, 8 | 16) {
        return Err(HeightmapError::UnsupportedPng {
            path: path.to_path_buf(),
            color: format!("{color:?}"),
            bits,
        });
    }
    let len = reader
        .output_buffer_size()
        .ok_or_else(|| HeightmapError::TooLarge {
            path: path.to_path_buf(),
            nx,
            ny,
        })?;
    let mut buf = vec![0u8; len];
    let frame = reader.next_frame(&mut buf).map_err(not_png)?;
    let stride = frame.line_size;
    let full = if bits == 16 { 65_535.0 } else { 255.0 };
    let mut values = vec![0.0; nx * ny];
    for r in 0..ny {
        let row = &buf[r * stride..(r + 1) * stride];
        let j = ny - 1 - r;
        for i in 0..nx {
            let v = if bits == 16 {
                u16::from_be_bytes([row[2 * i], row[2 * i + 1]]) as f64
            } else {
                row[i] as f64
            };
            values[j * nx + i] = v / full;
        }
    }
    Ok(HeightGrid { nx, ny, values })
}

fn read_csv(path: &Path, r: BufReader<File>) -> Result<HeightGrid, HeightmapError> {
    let mut rdr = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .trim(csv::Trim::All)
        .comment(Some(b'#'))
        .from_reader(r);
    // rows in file order (top = largest y), flipped at the end
    let mut rows: Vec<f64> = Vec::new();
    let mut nx = 0;
    let mut ny = 0;
    let mut record = csv::StringRecord::new();
    loop {
        match rdr.read_record(&mut record) {
            Ok(false) => break,
            Ok(true) => {}
            Err(e) => {
                return Err(HeightmapError::NotCsv {
                    path: path.to_path_buf(),
                    reason: e.to_string(),
                });
            }
        }
        let line = record.position().map_or(0, |p| p.line());
        // a line holding only blanks
        if record.len() == 1 && record[0].is_empty() {
            continue;
        }
        if ny == 0 {
            nx = record.len();
        }
        ny += 1;
        check_size(path, record.len().max(nx), ny)?;
        if record.len() != nx {
            return Err(HeightmapError::Ragged {
                path: path.to_path_buf(),
                row: line,
                expected: nx,
                got: record.len(),
            });
        }
        for (c, field) in record.iter().enumerate() {
            match field.parse::<f64>() {
                Ok(v) if v.is_finite() => rows.push(v),
                _ => {
                    return Err(HeightmapError::NotANumber {
                        path: path.to_path_buf(),
                        row: line,
                        column: c + 1,
                        text: field.to_string(),
                    });
                }
            }
        }
    }
    if ny == 0 {
        return Err(HeightmapError::Empty {
            path: path.to_path_buf(),
        });
    }
    // file order (top row first) to increasing y, in place
    for r in 0..ny / 2 {
        let (top, bottom) = rows.split_at_mut((ny - 1 - r) * nx);
        top[r * nx..(r + 1) * nx].swap_with_slice(&mut bottom[..nx]);
    }
    Ok(HeightGrid {
        nx,
        ny,
        values: rows,
    })
}

fn write_err(path: &Path, e: impl std::fmt::Display) -> HeightmapError {
    HeightmapError::Write {
        path: path.to_path_buf(),
        reason: e.to_string(),
    }
}

fn check_dims(path: &Path, nx: usize, ny: usize, len: usize) -> Result<(), HeightmapError> {
    if nx < 2 || ny < 2 {
        return Err(HeightmapError::TooSmall {
            path: path.to_path_buf(),
            nx,
            ny,
        });
    }
    check_size(path, nx, ny)?;
    if len != nx * ny {
        return Err(write_err(
            path,
            format!("{len} samples for a {nx} × {ny} grid"),
        ));
    }
    Ok(())
}

/// Writes a 16-bit greyscale PNG of `samples` (row-major by increasing y,
/// like [`HeightGrid::values`]; the top image row is the largest y).
pub fn write_png16(
    path: &Path,
    nx: usize,
    ny: usize,
    samples: &[u16],
) -> Result<(), HeightmapError> {
    check_dims(path, nx, ny, samples.len())?;
    let file = File::create(path).map_err(|e| write_err(path, e))?;
    let mut enc = png::Encoder::new(BufWriter::new(file), nx as u32, ny as u32);
    enc.set_color(png::ColorType::Grayscale);
    enc.set_depth(png::BitDepth::Sixteen);
    let mut writer = enc.write_header().map_err(|e| write_err(path, e))?;
    let mut bytes = Vec::with_capacity(2 * samples.len());
    for r in 0..ny {
        let j = ny - 1 - r;
        for v in &samples[j * nx..(j + 1) * nx] {
            bytes.extend_from_slice(&v.to_be_bytes());
        }
    }
    writer
        .write_image_data(&bytes)
        .map_err(|e| write_err(path, e))?;
    writer.finish().map_err(|e| write_err(path, e))
}

/// Writes a CSV grid of `values` (row-major by increasing y; the first line
/// is the largest y), each number in Rust's shortest form that reads back to
/// the same f64, so the round trip is exact. `header` lines are written first
/// as `#` comments.
pub fn write_csv(
    path: &Path,
    nx: usize,
    ny: usize,
    values: &[f64],
    header: &[String],
) -> Result<(), HeightmapError> {
    check_dims(path, nx, ny, values.len())?;
    let file = File::create(path).map_err(|e| write_err(path, e))?;
    let mut w = BufWriter::new(file);
    let mut out = || -> std::io::Result<()> {
        for h in header {
            writeln!(w, "# {h}")?;
        }
        for r in 0..ny {
            let j = ny - 1 - r;
            let row = &values[j * nx..(j + 1) * nx];
            for (i, v) in row.iter().enumerate() {
                if i > 0 {
                    w.write_all(b",")?;
                }
                write!(w, "{v:?}")?;
            }
            w.write_all(b"\n")?;
        }
        w.flush()
    };
    out().map_err(|e| write_err(path, e))
}
