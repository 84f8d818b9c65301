//! `--follow`: a file that is still being written (`candump -l` in another
//! terminal), followed by name like `tail -F`. At its end, wait for more; a
//! cancel ends it.
//!
//! Logs get rotated under a follower, and nothing may be lost to that:
//! - a new file at the path (rotated by rename and recreate, as logrotate
//!   does by default; deleted and recreated): the old file is read to its
//!   end, then the new one from its start;
//! - the file truncated (`copytruncate`; also truncated and written past
//!   where reading was, which the size alone does not show: the last bytes
//!   read are compared with what the file now holds there): read again from
//!   its start;
//! - the path gone: the old file is still read while it grows, and the path
//!   is waited for until a file comes back or Ctrl-C.
//!
//! A line left unfinished by a rotation or truncation is read as a line of
//! its own (a newline is put after it): its file ended there, as a file
//! ends without a final newline, so it is decoded as it stands, or
//! reported malformed with its line number, and counted. Dropping it would
//! lose it, and a line missing only its newline is whole; gluing it to the
//! next file's first line would lose that one too. Each of these events gets
//! a note on stderr.
//!
//! Identity (device and inode) and size are checked by path when the file
//! has no more data, once per poll; the last bytes read are compared also
//! before each read, so a rewrite is seen whenever it happened (a read of
//! at most `TAIL` bytes and two seeks: a followed file is read in large
//! chunks or waited on, never line by line).

use std::fs::{self, File, Metadata};
use std::io::{self, Read, Seek, SeekFrom, Write};
use std::path::PathBuf;
use std::time::Duration;

use super::cancel::{self, Cancel};

/// How many of the last bytes read are kept to see a rewrite: a few lines;
/// lines with timestamps do not repeat byte for byte at the same offset.
const TAIL: usize = 4096;

/// Which file a path names: device and inode.
type FileId = (u64, u64);

#[cfg(unix)]
fn file_id(meta: &Metadata) -> Option<FileId> {
    use std::os::unix::fs::MetadataExt;
    Some((meta.dev(), meta.ino()))
}

/// Without inodes, a replaced file is not told apart; truncation still is.
#[cfg(not(unix))]
fn file_id(_meta: &Metadata) -> Option<FileId> {
    None
}

/// Where notes go: stderr, or a test's list.
type Notes = Box<dyn FnMut(&str) + Send>;

/// A file followed by name, read to its end and then waited on.
pub struct Follow {
    path: PathBuf,
    file: File,
    id: Option<FileId>,
    /// Bytes read from `file`.
    pos: u64,
    /// The last bytes read from `file` (up to [`TAIL`]), and room to compare.
    tail: Vec<u8>,
    scratch: Vec<u8>,
    /// Bytes read since the last newline: an unfinished line.
    unfinished: u64,
    /// A NUL byte was read: a binary trace (BLF, pcap, MF4; text traces
    /// have none), which has no lines to finish or cut.
    binary: bool,
    /// A new file found at the path, read once `file` is finished.
    next: Option<(File, Option<FileId>)>,
    /// `file` had no more data: look at the path before reading on.
    at_end: bool,
    /// A newline to hand out after a line cut by a rotation or truncation.
    owe_newline: bool,
    /// The path was seen gone (noted once until a file is back).
    gone: bool,
    /// Bytes were handed out: a cancel now cuts the input.
    passed: bool,
    poll: Duration,
    cancel: Cancel,
    notes: Notes,
}

impl Follow {
    /// Follows `file` (opened from `path`) until `cancel` is set.
    pub fn new(path: PathBuf, file: File, cancel: Cancel) -> Self {
        let id = file.metadata().ok().as_ref().and_then(file_id);
        Follow {
            path,
            file,
            id,
            pos: 0,
            tail: Vec::new(),
            scratch: Vec::new(),
            unfinished: 0,
            binary: false,
            next: None,
            at_end: false,
            owe_newline: false,
            gone: false,
            passed: false,
            poll: Duration::from_millis(200),
            cancel,
            // The trace layer has no diagnostic log; these are rare, one
            // line each, and a failing stderr must not stop reading.
            notes: Box::new(|note| {
                let _ = writeln!(io::stderr().lock(), "{note}");
            }),
        }
    }

    fn note(&mut self, what: &str) {
        let note = format!("{}: {what}", self.path.display());
        (self.notes)(&note);
    }

    /// Bytes handed out from `file`.
    fn took(&mut self, data: &[u8]) {
        self.pos += data.len() as u64;
        self.passed = true;
        self.binary = self.binary || memchr::memchr(0, data).is_some();
        self.unfinished = match memchr::memrchr(b'\n', data) {
            _ if self.binary => 0,
            Some(i) => (data.len() - i - 1) as u64,
            None => self.unfinished + data.len() as u64,
        };
        let keep = data.len().min(TAIL);
        let drop = (self.tail.len() + keep).saturating_sub(TAIL);
        self.tail.drain(..drop);
        self.tail
            .extend_from_slice(data.get(data.len() - keep..).unwrap_or_default());
    }

    /// Reading goes on from the start of `file` (a new one, or the same one
    /// truncated).
    fn start_over(&mut self, what: &str) {
        let mut note = format!("{what}; reading it from its start");
        if self.unfinished > 0 {
            note.push_str(&format!(
                "; its last line before that ({} bytes, no newline) is read as a line of its own",
                self.unfinished
            ));
            self.owe_newline = true;
        }
        self.note(&note);
        self.pos = 0;
        self.tail.clear();
        self.unfinished = 0;
        self.at_end = false;
    }

    /// Whether `file` no longer holds what was read from it: truncated (the
    /// last bytes read are no longer there), or truncated and written again
    /// (they differ). Not by size alone: files in /proc say 0.
    fn rewritten(&mut self) -> io::Result<bool> {
        let k = self.tail.len();
        if k == 0 {
            return Ok(false);
        }
        self.scratch.resize(k, 0);
        self.file
            .seek(SeekFrom::Start(self.pos.saturating_sub(k as u64)))?;
        let same = match self.file.read_exact(&mut self.scratch) {
            Ok(()) => self.scratch == self.tail,
            Err(e) if e.kind() == io::ErrorKind::UnexpectedEof => false,
            Err(e) => return Err(e),
        };
        self.file.seek(SeekFrom::Start(self.pos))?;
        Ok(!same)
    }

    fn restart_truncated(&mut self) -> io::Result<()> {
        self.file.seek(SeekFrom::Start(0))?;
        self.start_over("truncated");
        Ok(())
    }

    /// At the end of `file`: a new file at the path, truncation, growth, or
    /// nothing yet (then `at_end` stays set).
    fn look(&mut self) -> io::Result<()> {
        match fs::metadata(&self.path) {
            Ok(meta) if meta.is_file() && file_id(&meta) == self.id => self.gone = false,
            Ok(meta) if meta.is_file() => {
                // Opened now, so a further rotation cannot take it away;
                // read once the old file is finished.
                match File::open(&self.path) {
                    Ok(file) => {
                        let id = file.metadata().ok().as_ref().and_then(file_id);
                        self.next = Some((file, id));
                        self.at_end = false;
                        self.gone = false;
                        return Ok(());
                    }
                    // Gone again (tried next time), or not readable (told once).
                    Err(e) if e.kind() == io::ErrorKind::NotFound => {}
                    Err(e) => {
                        if !self.gone {
                            self.gone = true;
                            self.note(&format!(
                                "a new file at this path cannot be opened ({}); waiting for one that can",
                                e.kind()
                            ));
                        }
                    }
                }
            }
            // Gone, or not a regular file (opening a FIFO could block).
            _ => {
                if !self.gone {
                    self.gone = true;
                    self.note("gone (removed or renamed); waiting for a file at this path");
                }
            }
        }
        if self.rewritten()? {
            self.restart_truncated()?;
        } else if self.file.metadata()?.len() > self.pos {
            self.at_end = false;
        }
        Ok(())
    }

    /// A cancel: the end, or a cut (see `cancel`), with a note for a line
    /// that was not finished.
    fn stop(&mut self) -> io::Result<usize> {
        if !self.passed {
            return Ok(0);
        }
        if self.unfinished > 0 {
            let n = self.unfinished;
            self.unfinished = 0;
            self.note(&format!(
                "stopped inside a line: its {n} bytes read so far (no newline yet) are not read"
            ));
        }
        Err(cancel::cancelled())
    }
}

impl Read for Follow {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        if buf.is_empty() {
            return Ok(0);
        }
        loop {
            // Before a cancel too: the file of that line did end.
            if self.owe_newline {
                self.owe_newline = false;
                self.passed = true;
                buf[0] = b'\n';
                return Ok(1);
            }
            if self.cancel.is_cancelled() {
                return self.stop();
            }
            // Every look comes after a poll's wait: a file that keeps
            // changing (or says it grew and has nothing) is never spun on.
            if self.at_end {
                std::thread::sleep(self.poll);
                if !self.cancel.is_cancelled() {
                    self.look()?;
                }
                continue;
            }
            if self.rewritten()? {
                self.restart_truncated()?;
                continue;
            }
            let n = self.file.read(buf)?;
            if let Some(data) = buf.get(..n).filter(|d| !d.is_empty()) {
                self.took(data);
                return Ok(n);
            }
            if let Some((file, id)) = self.next.take() {
                self.file = file;
                self.id = id;
                self.start_over("a new file at this path (rotated or recreated)");
                continue;
            }
            self.at_end = true;
        }
    }
}

#[cfg(test)]
mod tests {
    //! One thread: each change to the file is made while the reader is at
    //! its end, before the next read, as a writer does while `--follow`
    //! waits. Through the binary with a writer alongside:
    //! tests/integration/follow.rs.
    use super::*;
    use std::path::Path;
    use std::sync::{Arc, Mutex};

    fn follow(path: &Path) -> (Follow, Arc<Mutex<Vec<String>>>, Cancel) {
        let cancel = Cancel::new();
        let mut f = Follow::new(
            path.to_path_buf(),
            File::open(path).unwrap(),
            cancel.clone(),
        );
        f.poll = Duration::from_millis(1);
        let notes = Arc::new(Mutex::new(Vec::new()));
        let sink = Arc::clone(&notes);
        f.notes = Box::new(move |n| sink.lock().unwrap().push(n.to_string()));
        (f, notes, cancel)
    }

    /// Reads until `want` bytes came.
    fn read_n(f: &mut Follow, want: usize) -> String {
        let mut out = Vec::new();
        let mut buf = [0u8; 64];
        while out.len() < want {
            let n = f.read(&mut buf).unwrap();
            out.extend_from_slice(&buf[..n]);
        }
        String::from_utf8(out).unwrap()
    }

    fn append(path: &Path, text: &str) {
        let mut w = fs::OpenOptions::new().append(true).open(path).unwrap();
        w.write_all(text.as_bytes()).unwrap();
    }

    #[test]
    fn follow_reads_what_is_appended() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("grow.log");
        fs::write(&path, "first\n").unwrap();
        let (mut f, notes, _) = follow(&path);
        assert_eq!(read_n(&mut f, 6), "first\n");
        append(&path, "second\n");
        assert_eq!(read_n(&mut f, 7), "second\n");
        assert!(notes.lock().unwrap().is_empty());
    }

    #[test]
    fn a_renamed_and_recreated_file_is_finished_then_the_new_one_read() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("can.log");
        fs::write(&path, "one\n").unwrap();
        let (mut f, notes, _) = follow(&path);
        assert_eq!(read_n(&mut f, 4), "one\n");
        fs::rename(&path, dir.path().join("can.log.1")).unwrap();
        // The writer still had the old file open.
        append(&dir.path().join("can.log.1"), "two\n");
        fs::write(&path, "three\n").unwrap();
        assert_eq!(read_n(&mut f, 10), "two\nthree\n");
        let notes = notes.lock().unwrap();
        assert_eq!(notes.len(), 1, "{notes:?}");
        assert!(notes[0].contains("a new file at this path"), "{notes:?}");
    }

    #[test]
    fn a_file_truncated_and_rewritten_larger_is_read_again_from_its_start() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("can.log");
        fs::write(&path, "one\n").unwrap();
        let (mut f, notes, _) = follow(&path);
        assert_eq!(read_n(&mut f, 4), "one\n");
        fs::write(&path, "two\nthree\n").unwrap();
        assert_eq!(read_n(&mut f, 10), "two\nthree\n");
        assert!(notes.lock().unwrap()[0].contains("truncated"));
    }

    #[test]
    fn a_line_cut_by_a_truncation_is_a_line_of_its_own() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("can.log");
        fs::write(&path, "one\nha").unwrap();
        let (mut f, notes, _) = follow(&path);
        assert_eq!(read_n(&mut f, 6), "one\nha");
        fs::write(&path, "two\n").unwrap();
        assert_eq!(read_n(&mut f, 5), "\ntwo\n");
        let notes = notes.lock().unwrap();
        assert!(notes[0].contains("(2 bytes, no newline)"), "{notes:?}");
    }

    /// A binary trace (a NUL byte in it) has no lines: a truncation gets
    /// no newline between the files and a cancel no note about a line.
    #[test]
    fn a_binary_file_is_never_cut_into_lines() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("can.pcap");
        fs::write(&path, b"PCAP\x00\x00ab").unwrap();
        let (mut f, notes, _) = follow(&path);
        assert_eq!(read_n(&mut f, 8), "PCAP\0\0ab");
        fs::write(&path, b"cd").unwrap();
        assert_eq!(read_n(&mut f, 2), "cd", "no newline put in");
        {
            let notes = notes.lock().unwrap();
            assert!(notes[0].contains("truncated"), "{notes:?}");
            assert!(!notes[0].contains("line"), "{notes:?}");
        }
        fs::write(&path, b"\x00x").unwrap();
        let (mut f, notes, cancel) = follow(&path);
        assert_eq!(read_n(&mut f, 2), "\0x");
        cancel.cancel();
        assert!(f.read(&mut [0u8; 8]).is_err());
        assert!(notes.lock().unwrap().is_empty(), "no line was cut");
    }

    #[test]
    fn a_deleted_file_is_waited_for_until_it_comes_back() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("can.log");
        fs::write(&path, "one\n").unwrap();
        let (mut f, notes, _) = follow(&path);
        assert_eq!(read_n(&mut f, 4), "one\n");
        fs::remove_file(&path).unwrap();
        let writer = {
            let (path, notes) = (path.clone(), Arc::clone(&notes));
            std::thread::spawn(move || {
                // Recreated only once the reader has seen it gone.
                while notes.lock().unwrap().is_empty() {
                    std::thread::sleep(Duration::from_millis(1));
                }
                fs::write(&path, "two\n").unwrap();
            })
        };
        assert_eq!(read_n(&mut f, 4), "two\n");
        writer.join().unwrap();
        let notes = notes.lock().unwrap();
        assert!(notes[0].contains("gone"), "{notes:?}");
        assert!(notes[1].contains("a new file"), "{notes:?}");
    }

    #[test]
    fn a_cancel_cuts_an_unfinished_line_and_ends_cleanly_otherwise() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("can.log");
        fs::write(&path, "one\ntw").unwrap();
        let (mut f, notes, cancel) = follow(&path);
        assert_eq!(read_n(&mut f, 6), "one\ntw");
        cancel.cancel();
        let err = f.read(&mut [0u8; 8]).unwrap_err();
        assert!(cancel::is_cancelled(&err), "{err}");
        assert!(notes.lock().unwrap()[0].contains("2 bytes"));
        // Nothing read yet: nothing cut, a plain end.
        let (mut f, _, cancel) = follow(&path);
        cancel.cancel();
        assert_eq!(f.read(&mut [0u8; 8]).unwrap(), 0);
    }
}
