//! Limits on what input may cost: file sizes, threads, steps. Each is stated
//! in `docs/reliability.md` and refused at once, with the number, when
//! exceeded.

use std::io::Read;
use std::path::Path;

/// The largest scenario, study or URDF file read (bytes): 16 MiB.
pub const MAX_TEXT_FILE_BYTES: u64 = 16 << 20;

/// The largest heightmap file read (bytes): 512 MiB (a CSV of 16384² samples
/// written with a few digits each fits).
pub const MAX_HEIGHTMAP_FILE_BYTES: u64 = 512 << 20;

/// The most steps one run may take (`duration_s / dt_s`): 10⁹ (some 6 days
/// of simulated time at 0.5 ms).
pub const MAX_STEPS: u64 = 1_000_000_000;

/// Reads a whole text file of at most `max` bytes. A longer file (or an
/// endless one, such as `/dev/zero`) is refused after reading `max + 1`
/// bytes, naming the limit.
pub fn read_text_capped(path: &Path, max: u64) -> std::io::Result<String> {
    let file = std::fs::File::open(path)?;
    let mut buf = Vec::new();
    file.take(max + 1).read_to_end(&mut buf)?;
    if buf.len() as u64 > max {
        return Err(std::io::Error::other(format!(
            "the file is larger than the {} MiB a quadsim input may be",
            max >> 20
        )));
    }
    String::from_utf8(buf).map_err(|e| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("not UTF-8 text: {e}"),
        )
    })
}

/// The worker threads a run may use: the machine's parallelism. A request
/// above it is capped there, with a message saying so; 0 asks for it.
pub fn capped_threads(requested: usize) -> (usize, Option<String>) {
    let n = std::thread::available_parallelism().map_or(1, |n| n.get());
    if requested > n {
        (
            n,
            Some(format!(
                "--threads {requested}: this machine runs {n} threads in parallel; using {n}"
            )),
        )
    } else {
        (requested, None)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn endless_file_is_refused() {
        let e = read_text_capped(Path::new("/dev/zero"), 1024).unwrap_err();
        assert!(e.to_string().contains("larger than"), "{e}");
    }

    #[test]
    fn threads_are_capped() {
        let (n, msg) = capped_threads(100_000);
        assert!(n < 100_000 && msg.is_some());
        assert_eq!(capped_threads(0), (0, None));
    }
}
