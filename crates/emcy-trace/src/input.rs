//! Opening inputs: files, stdin, and gzip read transparently (by magic bytes,
//! never by file name, so `trace.log.gz` piped through stdin works too).

use std::fs::File;
use std::io::{self, BufReader, Read};
use std::path::{Path, PathBuf};

use super::cancel::{self, Cancel, Interruptible, StopOnCancel};
use super::follow::Follow;

const GZIP_MAGIC: [u8; 2] = [0x1f, 0x8b];

/// Where an input comes from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Source {
    /// Standard input (`-`).
    Stdin,
    /// A file.
    Path(PathBuf),
}

impl Source {
    /// `-` means stdin, as in every Unix filter.
    pub fn from_arg(arg: &Path) -> Source {
        if arg.as_os_str() == "-" {
            Source::Stdin
        } else {
            Source::Path(arg.to_path_buf())
        }
    }

    /// The name used in reports and diagnostics.
    pub fn display_name(&self) -> String {
        match self {
            Source::Stdin => "<stdin>".to_string(),
            Source::Path(p) => p.display().to_string(),
        }
    }
}

/// An opened input: a byte stream already decompressed if it was gzip.
pub struct Opened {
    /// The bytes, decompressed.
    pub reader: Box<dyn Read + Send>,
    /// Whether the input was gzip.
    pub gzip: bool,
    /// Size on disk, for regular files.
    pub size: Option<u64>,
}

/// How a source is read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ReadMode {
    /// To its end; Ctrl-C stops at the next read.
    Finite,
    /// A stream that may block (stdin from candump): Ctrl-C ends it even
    /// while it waits.
    Live,
    /// `--follow`: a growing file; its end is waited past until Ctrl-C.
    Follow,
}

/// Opens a source to be read the given way; a cancel of `cancel` ends it.
/// Errors carry a message fit for `error: NAME: message`.
pub fn open(source: &Source, mode: ReadMode, cancel: &Cancel) -> io::Result<Opened> {
    let stop = |inner: Box<dyn Read + Send>| -> Box<dyn Read + Send> {
        Box::new(StopOnCancel::new(inner, cancel.clone()))
    };
    let (raw, size): (Box<dyn Read + Send>, Option<u64>) = match source {
        Source::Stdin if mode == ReadMode::Finite => (stop(Box::new(io::stdin())), None),
        Source::Stdin => (
            Box::new(Interruptible::new(Box::new(io::stdin()), cancel.clone())),
            None,
        ),
        // Opening a FIFO waits for a writer, and reading one waits as long as
        // the bus is quiet: both happen on a reading thread of their own, so
        // a signal (a service manager's SIGTERM) ends the input at once.
        Source::Path(path) if mode != ReadMode::Follow && is_stream(path) => (
            Box::new(Interruptible::new(
                Box::new(OpenOnRead::new(path.clone())),
                cancel.clone(),
            )),
            None,
        ),
        Source::Path(path) => {
            let file = File::open(path)?;
            let meta = file.metadata()?;
            if meta.is_dir() {
                return Err(io::Error::new(
                    io::ErrorKind::InvalidInput,
                    "is a directory",
                ));
            }
            match mode {
                ReadMode::Follow => (
                    Box::new(Follow::new(path.clone(), file, cancel.clone())),
                    None,
                ),
                ReadMode::Live => (
                    Box::new(Interruptible::new(Box::new(file), cancel.clone())),
                    None,
                ),
                ReadMode::Finite => {
                    let size = meta.is_file().then_some(meta.len());
                    (stop(Box::new(file)), size)
                }
            }
        }
    };
    let mut opened = match sniff_gzip(raw) {
        // Cut by a cancel while its first bytes were looked at: no line was
        // read, so the input is empty rather than unreadable.
        Err(e) if cancel::is_cancelled(&e) => sniff_gzip(Box::new(io::empty()))?,
        opened => opened?,
    };
    opened.size = size;
    Ok(opened)
}

/// True when `path` names a FIFO, a character device (a terminal, a serial
/// port) or a socket: a stream that may wait for data, as a pipe does.
/// Asked of the file's metadata, which never waits (opening a FIFO does).
pub fn is_stream(path: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        std::fs::metadata(path).is_ok_and(|m| {
            let t = m.file_type();
            t.is_fifo() || t.is_char_device() || t.is_socket()
        })
    }
    #[cfg(not(unix))]
    {
        let _ = path;
        false
    }
}

/// A file opened at its first read, so on the thread that reads it (see
/// [`Interruptible`]): there a FIFO's open may wait for its writer.
struct OpenOnRead {
    path: PathBuf,
    file: Option<File>,
}

impl OpenOnRead {
    fn new(path: PathBuf) -> Self {
        OpenOnRead { path, file: None }
    }
}

impl Read for OpenOnRead {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let file = match &mut self.file {
            Some(file) => file,
            None => self.file.insert(File::open(&self.path)?),
        };
        file.read(buf)
    }
}

/// True when stdin is a pipe, terminal or socket (a live stream), false for a
/// redirected regular file.
pub fn stdin_is_stream() -> bool {
    #[cfg(unix)]
    {
        use std::os::fd::AsFd;
        use std::os::unix::fs::FileTypeExt;
        let stdin = io::stdin();
        let Ok(fd) = stdin.as_fd().try_clone_to_owned() else {
            return false;
        };
        match File::from(fd).metadata() {
            Ok(m) => {
                let t = m.file_type();
                t.is_fifo() || t.is_char_device() || t.is_socket()
            }
            Err(_) => false,
        }
    }
    #[cfg(not(unix))]
    {
        use std::io::IsTerminal;
        io::stdin().is_terminal()
    }
}

/// Reads up to two bytes to look for the gzip magic, then puts them back in
/// front of the stream. Works on pipes that deliver one byte at a time.
pub fn sniff_gzip(raw: Box<dyn Read + Send>) -> io::Result<Opened> {
    let (reader, gzip) = sniff_gzip_generic(raw)?;
    Ok(Opened {
        reader: match reader {
            Sniffed::Plain(r) => Box::new(r),
            Sniffed::Gzip(r) => Box::new(r),
        },
        gzip,
        size: None,
    })
}

/// A stream with its first bytes put back: plain, or decompressed.
pub enum Sniffed<R> {
    /// Not gzip: read as it is.
    Plain(Peeked<R>),
    /// Every member of the stream (`cat a.gz b.gz` is valid gzip).
    Gzip(Box<Members<BufReader<Peeked<R>>>>),
}

type Peeked<R> = io::Chain<io::Take<io::Cursor<[u8; 2]>>, R>;

impl<R: Read> Read for Sniffed<R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        match self {
            Sniffed::Plain(r) => r.read(buf),
            Sniffed::Gzip(r) => r.read(buf),
        }
    }
}

/// [`sniff_gzip`] for any reader: the stream and whether it was gzip.
pub fn sniff_gzip_generic<R: Read>(mut raw: R) -> io::Result<(Sniffed<R>, bool)> {
    let mut head = [0u8; 2];
    let mut got = 0;
    while got < head.len() {
        match raw.read(&mut head[got..]) {
            Ok(0) => break,
            Ok(n) => got += n,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(e),
        }
    }
    let stream = io::Cursor::new(head).take(got as u64).chain(raw);
    if got == 2 && head == GZIP_MAGIC {
        let members = Members::new(BufReader::with_capacity(256 * 1024, stream));
        Ok((Sniffed::Gzip(Box::new(members)), true))
    } else {
        Ok((Sniffed::Plain(stream), false))
    }
}

/// The members of a gzip stream, one after another, and what GNU gzip
/// accepts after the last: nothing, or zero bytes (tape and block devices
/// pad with them). Anything else after a member is an error, as it is for
/// gzip. flate2's MultiGzDecoder takes the zeros for a broken header; its
/// single-member bufread decoder reads exactly one member, so the bytes
/// after it can be looked at here.
pub struct Members<R> {
    decoder: Option<flate2::bufread::GzDecoder<R>>,
}

impl<R: io::BufRead> Members<R> {
    fn new(inner: R) -> Self {
        Members {
            decoder: Some(flate2::bufread::GzDecoder::new(inner)),
        }
    }
}

impl<R: io::BufRead> Read for Members<R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        loop {
            let Some(decoder) = &mut self.decoder else {
                return Ok(0);
            };
            let n = decoder.read(buf)?;
            if n > 0 || buf.is_empty() {
                return Ok(n);
            }
            // A member ended: another, zero padding, the end, or garbage.
            let Some(mut inner) = self.decoder.take().map(|d| d.into_inner()) else {
                return Ok(0);
            };
            loop {
                let head = match inner.fill_buf() {
                    Ok(head) => head,
                    Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
                    Err(e) => return Err(e),
                };
                if head.is_empty() {
                    return Ok(0);
                }
                if head.first() == Some(&0) {
                    let zeros = head.iter().take_while(|b| **b == 0).count();
                    inner.consume(zeros);
                    continue;
                }
                if head.first() == Some(&GZIP_MAGIC[0]) {
                    self.decoder = Some(flate2::bufread::GzDecoder::new(inner));
                    break;
                }
                return Err(io::Error::new(
                    io::ErrorKind::InvalidData,
                    "trailing garbage after gzip data",
                ));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    fn read_all(data: Vec<u8>) -> (Vec<u8>, bool) {
        let mut opened = sniff_gzip(Box::new(io::Cursor::new(data))).unwrap();
        let mut out = Vec::new();
        opened.reader.read_to_end(&mut out).unwrap();
        (out, opened.gzip)
    }

    #[test]
    fn plain_text_passes_through() {
        assert_eq!(read_all(b"abc".to_vec()), (b"abc".to_vec(), false));
        assert_eq!(read_all(b"a".to_vec()), (b"a".to_vec(), false));
        assert_eq!(read_all(Vec::new()), (Vec::new(), false));
    }

    #[test]
    fn gzip_is_decompressed_including_concatenated_members() {
        let mut gz = Vec::new();
        for part in [&b"hello "[..], b"world"] {
            let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
            enc.write_all(part).unwrap();
            gz.extend(enc.finish().unwrap());
        }
        assert_eq!(read_all(gz), (b"hello world".to_vec(), true));
    }

    fn gz(part: &[u8]) -> Vec<u8> {
        let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
        enc.write_all(part).unwrap();
        enc.finish().unwrap()
    }

    fn read_result(data: Vec<u8>) -> io::Result<Vec<u8>> {
        let mut opened = sniff_gzip(Box::new(io::Cursor::new(data)))?;
        let mut out = Vec::new();
        opened.reader.read_to_end(&mut out).map(|_| out)
    }

    #[test]
    fn zero_padding_after_gzip_is_accepted_as_gnu_gzip_does() {
        let mut padded = gz(b"hello ");
        padded.extend([0u8; 512]);
        assert_eq!(read_result(padded.clone()).unwrap(), b"hello ");
        // Between members too (concatenated padded files).
        padded.extend(gz(b"world"));
        padded.extend([0u8; 3]);
        assert_eq!(read_result(padded).unwrap(), b"hello world");
    }

    #[test]
    fn anything_else_after_gzip_is_an_error_after_the_data() {
        for junk in [&b"garbage\n"[..], &[0, 0, 7][..], &[0x1f, 0x00][..]] {
            let mut data = gz(b"hello");
            data.extend_from_slice(junk);
            let mut opened = sniff_gzip(Box::new(io::Cursor::new(data))).unwrap();
            let mut out = Vec::new();
            let err = opened.reader.read_to_end(&mut out).unwrap_err();
            assert_eq!(
                out, b"hello",
                "{junk:?}: the data before it is read ({err})"
            );
        }
    }

    #[test]
    fn directories_are_refused() {
        let err = match open(
            &Source::Path(PathBuf::from(".")),
            ReadMode::Finite,
            &Cancel::new(),
        ) {
            Err(e) => e,
            Ok(_) => panic!("opened a directory"),
        };
        assert_eq!(err.to_string(), "is a directory");
    }

    #[cfg(unix)]
    #[test]
    fn devices_are_streams_files_and_directories_are_not() {
        assert!(is_stream(Path::new("/dev/null")));
        assert!(!is_stream(Path::new(".")));
        assert!(!is_stream(Path::new("Cargo.toml")));
        assert!(!is_stream(Path::new("no such file")));
    }

    /// A FIFO given by name is opened and read on a thread of its own: a
    /// cancel ends the input while the open still waits for a writer (the
    /// input is then empty, nothing was cut).
    #[cfg(unix)]
    #[test]
    fn a_cancel_ends_a_fifo_that_no_writer_opened() {
        let dir = tempfile::tempdir().expect("a temp dir");
        let fifo = dir.path().join("can0.fifo");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        assert!(made.is_ok_and(|s| s.success()), "mkfifo");
        let cancel = Cancel::new();
        let (tx, rx) = std::sync::mpsc::channel();
        let reading = cancel.clone();
        std::thread::spawn(move || {
            let read = open(&Source::Path(fifo), ReadMode::Finite, &reading).and_then(|mut o| {
                let mut all = Vec::new();
                o.reader.read_to_end(&mut all).map(|_| all)
            });
            let _ = tx.send(read.map_err(|e| e.to_string()));
        });
        std::thread::sleep(std::time::Duration::from_millis(100));
        cancel.cancel();
        let read = rx
            .recv_timeout(std::time::Duration::from_secs(10))
            .expect("the open ended by the cancel");
        assert_eq!(read, Ok(Vec::new()));
    }
}
