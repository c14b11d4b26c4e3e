//! Simulated trajectories as CSV: `t,U1,U2,U3,h1,h2,h3,tip_x,tip_y,tip_z` in SI units, the
//! columns of the reference data and of measured experiment files.

use std::path::{Path, PathBuf};
use std::sync::mpsc::{Receiver, SyncSender, sync_channel};
use std::thread::JoinHandle;

use super::csv::{BYTES_PER_NUMBER, format_row};
use super::file::{AtomicFile, FileError};
use crate::simulation::Sample;

const COLUMNS: [&str; 10] = [
    "t", "U1", "U2", "U3", "h1", "h2", "h3", "tip_x", "tip_y", "tip_z",
];

/// Writes `samples` to `path` atomically.
pub fn write(path: &Path, samples: &[Sample]) -> Result<(), FileError> {
    let mut stream = Stream::create(path)?;
    samples.iter().for_each(|s| stream.push(s));
    stream.finish()
}

/// Samples handed to the writing thread at a time: few enough that the last chunk, formatted
/// after the run, costs tens of microseconds; many enough that handing over is rare.
const CHUNK: usize = 250;

/// Chunks that may wait for the writing thread before [`Stream::push`] waits in turn.
const QUEUE: usize = 64;

/// A trajectory written while it is computed. Samples go in chunks to a thread that formats
/// them (the bulk of writing a CSV) and appends them to an [`AtomicFile`], so on two cores the
/// file costs the run little more than its last chunk. The file appears whole at
/// [`Stream::finish`] or not at all: dropped unfinished, the temporary file is removed.
pub struct Stream {
    path: PathBuf,
    chunk: Vec<Sample>,
    /// `None` once the writing thread has stopped on an error, which `finish` reports.
    sender: Option<SyncSender<Vec<Sample>>>,
    writer: Option<JoinHandle<Result<AtomicFile, FileError>>>,
}

impl Stream {
    /// Creates the temporary file (so a path that cannot be written fails before the run) and
    /// starts the writing thread.
    pub fn create(path: &Path) -> Result<Stream, FileError> {
        let file = AtomicFile::create(path)?;
        let (sender, receiver) = sync_channel(QUEUE);
        let writer = std::thread::Builder::new()
            .name("csv writer".into())
            .spawn(move || write_chunks(file, receiver))
            .map_err(|e| FileError::new(path, format!("cannot start the writing thread: {e}")))?;
        Ok(Stream {
            path: path.to_path_buf(),
            chunk: Vec::with_capacity(CHUNK),
            sender: Some(sender),
            writer: Some(writer),
        })
    }

    /// Appends one row.
    pub fn push(&mut self, sample: &Sample) {
        self.chunk.push(*sample);
        if self.chunk.len() == CHUNK {
            self.hand_over();
        }
    }

    fn hand_over(&mut self) {
        let full = std::mem::replace(&mut self.chunk, Vec::with_capacity(CHUNK));
        if let Some(sender) = &self.sender
            && sender.send(full).is_err()
        {
            self.sender = None;
        }
    }

    /// Writes the rows still held, waits for the writing thread and moves the file into place.
    pub fn finish(mut self) -> Result<(), FileError> {
        if !self.chunk.is_empty() {
            self.hand_over();
        }
        self.sender = None;
        let writer = self.writer.take().expect("a Stream finishes once");
        match writer.join() {
            Ok(file) => file?.commit(),
            Err(_) => Err(FileError::new(&self.path, "the writing thread stopped")),
        }
    }
}

impl Drop for Stream {
    /// Unfinished: stops the writing thread, whose file then removes itself.
    fn drop(&mut self) {
        self.sender = None;
        if let Some(writer) = self.writer.take() {
            let _ = writer.join();
        }
    }
}

/// The writing thread: the header, then each chunk formatted into one reused buffer and
/// appended; returns the file to be committed once the sender is gone.
fn write_chunks(
    mut file: AtomicFile,
    chunks: Receiver<Vec<Sample>>,
) -> Result<AtomicFile, FileError> {
    let mut text = COLUMNS.join(",").into_bytes();
    text.push(b'\n');
    file.write(&text)?;
    text = Vec::with_capacity(CHUNK * COLUMNS.len() * BYTES_PER_NUMBER);
    let mut number = zmij::Buffer::new();
    for chunk in chunks {
        text.clear();
        for s in &chunk {
            let [u1, u2, u3] = s.u;
            let [h1, h2, h3] = s.h;
            let [x, y, z] = s.tip;
            format_row(
                &mut text,
                &mut number,
                &[s.t, u1, u2, u3, h1, h2, h3, x, y, z],
            );
        }
        file.write(&text)?;
    }
    Ok(file)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::csv::Table;

    fn sample(k: usize) -> Sample {
        let v = k as f64;
        Sample {
            t: v * 1e-3,
            u: [v.sin(), -v, 1.0 / (v + 0.5)],
            h: [v * 1.3e-6, -v * 7e-7, v.sqrt() * 1e-6],
            tip: [v.cos() * 1e-4, 2e-5, f64::MIN_POSITIVE * v],
        }
    }

    #[test]
    fn streamed_rows_read_back_bit_for_bit_and_in_order() {
        let dir = std::env::temp_dir().join(format!("hasel-traj-{}", std::process::id()));
        let path = dir.join("run.csv");
        // several chunks and a part-filled last one
        let samples: Vec<Sample> = (0..3 * CHUNK + 7).map(sample).collect();
        write(&path, &samples).unwrap();
        let back = Table::read(&path).unwrap();
        assert_eq!(back.header, COLUMNS);
        assert_eq!(back.rows.len(), samples.len());
        for (row, s) in back.rows.iter().zip(&samples) {
            let want = [s.t, s.u[0], s.u[1], s.u[2], s.h[0], s.h[1], s.h[2]];
            let want = want.iter().chain(&s.tip).map(|v| v.to_bits());
            assert!(row.iter().map(|v| v.to_bits()).eq(want));
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn an_unfinished_stream_leaves_the_old_file_and_no_temporary() {
        let dir = std::env::temp_dir().join(format!("hasel-traj-drop-{}", std::process::id()));
        let path = dir.join("run.csv");
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(&path, "old\n").unwrap();
        let mut stream = Stream::create(&path).unwrap();
        (0..2 * CHUNK).for_each(|k| stream.push(&sample(k)));
        drop(stream); // a run that failed half-way
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "old\n");
        assert_eq!(crate::io::file::file_names(&dir), ["run.csv"]);
        // a path that cannot be a file fails at once, naming it
        let e = Stream::create(&dir).err().unwrap();
        assert!(e.to_string().starts_with(&dir.display().to_string()), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
