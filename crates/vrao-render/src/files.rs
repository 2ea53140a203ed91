//! Reading the files a user names: scenes, models, their materials and textures, glTF
//! buffers and images, environment maps, bench and frontier files. Every one is read here,
//! through [`read_regular_file`], so that each is
//!
//! - a regular file: the path (symlinks followed) is looked at before it is opened, and a
//!   directory, character or block device (`/dev/zero`), FIFO or socket is refused at once,
//!   named as what it is, without opening it (opening a FIFO would wait for a writer);
//! - bounded by the bytes actually read, not by what the file's metadata says (a device
//!   says 0, a file may grow while it is read): at most `limit + 1` bytes are read, and a
//!   file that has more is refused;
//! - named in the error: [`FileError`] carries the path and a typed [`FileProblem`].

use std::fmt;
use std::io::Read;
use std::path::{Path, PathBuf};
use vrao_ao::Error;

/// The largest model, texture, environment map, glTF buffer or image file read (1 GiB).
pub const MAX_FILE_BYTES: u64 = 1 << 30;

/// The largest text file that configures a run (a scene file, a bench or frontier file;
/// 64 MiB, far more than any of them holds).
pub const MAX_TEXT_BYTES: u64 = 64 << 20;

/// Why a file cannot be read.
#[derive(Debug)]
pub enum FileProblem {
    /// Nothing is at the path.
    Missing,
    /// Something other than a regular file is at the path: "a directory", "a FIFO
    /// (named pipe)", "a character device", "a block device", "a socket".
    NotRegular(&'static str),
    /// The file holds more than the limit (`bytes` is what the metadata said, or the
    /// limit + 1 when the file grew past it while being read).
    TooLarge {
        /// Bytes found.
        bytes: u64,
        /// The most allowed.
        limit: u64,
    },
    /// Text that is not UTF-8, at this byte.
    NotUtf8 {
        /// The byte offset of the first invalid sequence.
        at: usize,
    },
    /// The operating system refused (permissions, a symlink loop, an I/O error).
    Io(std::io::Error),
}

impl fmt::Display for FileProblem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            FileProblem::Missing => write!(f, "no such file"),
            FileProblem::NotRegular(what) => write!(f, "is {what}, not a regular file"),
            FileProblem::TooLarge { bytes, limit } => {
                write!(f, "{bytes} bytes, more than vrao's limit of {limit}")
            }
            FileProblem::NotUtf8 { at } => write!(f, "is not UTF-8 text (byte {at})"),
            FileProblem::Io(e) => write!(f, "cannot read: {e}"),
        }
    }
}

/// A file that cannot be read, and why.
#[derive(Debug)]
pub struct FileError {
    /// The path as given.
    pub path: PathBuf,
    /// What is wrong.
    pub problem: FileProblem,
}

impl fmt::Display for FileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.path.display(), self.problem)
    }
}

impl std::error::Error for FileError {}

impl From<FileError> for Error {
    fn from(e: FileError) -> Error {
        Error::in_file(&e.path, e.problem.to_string())
    }
}

impl FileError {
    fn new(path: &Path, problem: FileProblem) -> FileError {
        FileError { path: path.to_path_buf(), problem }
    }
}

/// What kind of thing `metadata` describes, when it is not a regular file.
fn not_regular(metadata: &std::fs::Metadata) -> Option<&'static str> {
    let kind = metadata.file_type();
    if kind.is_file() {
        return None;
    }
    if kind.is_dir() {
        return Some("a directory");
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if kind.is_fifo() {
            return Some("a FIFO (named pipe)");
        }
        if kind.is_char_device() {
            return Some("a character device");
        }
        if kind.is_block_device() {
            return Some("a block device");
        }
        if kind.is_socket() {
            return Some("a socket");
        }
    }
    Some("not a file")
}

/// Looks at `path` (following symlinks) without opening it: its size when it is a regular
/// file, else what it is.
pub fn check_regular_file(path: &Path) -> Result<u64, FileError> {
    let metadata = std::fs::metadata(path).map_err(|e| {
        let problem = if e.kind() == std::io::ErrorKind::NotFound { FileProblem::Missing } else { FileProblem::Io(e) };
        FileError::new(path, problem)
    })?;
    match not_regular(&metadata) {
        Some(what) => Err(FileError::new(path, FileProblem::NotRegular(what))),
        None => Ok(metadata.len()),
    }
}

/// The bytes of the regular file at `path`, at most `limit` of them (see the module
/// documentation): anything else at the path, or a file with more bytes, is refused.
pub fn read_regular_file(path: &Path, limit: u64) -> Result<Vec<u8>, FileError> {
    let size = check_regular_file(path)?;
    if size > limit {
        return Err(FileError::new(path, FileProblem::TooLarge { bytes: size, limit }));
    }
    let file = std::fs::File::open(path).map_err(|e| FileError::new(path, FileProblem::Io(e)))?;
    // What was opened is what was looked at (the path may have changed in between).
    let opened = file.metadata().map_err(|e| FileError::new(path, FileProblem::Io(e)))?;
    if let Some(what) = not_regular(&opened) {
        return Err(FileError::new(path, FileProblem::NotRegular(what)));
    }
    let mut bytes = Vec::with_capacity(size.min(limit) as usize);
    file.take(limit.saturating_add(1)).read_to_end(&mut bytes).map_err(|e| FileError::new(path, FileProblem::Io(e)))?;
    if bytes.len() as u64 > limit {
        return Err(FileError::new(path, FileProblem::TooLarge { bytes: bytes.len() as u64, limit }));
    }
    Ok(bytes)
}

/// The regular file at `path` as UTF-8 text, at most `limit` bytes ([`read_regular_file`]).
pub fn read_regular_file_to_string(path: &Path, limit: u64) -> Result<String, FileError> {
    let bytes = read_regular_file(path, limit)?;
    String::from_utf8(bytes)
        .map_err(|e| FileError::new(path, FileProblem::NotUtf8 { at: e.utf8_error().valid_up_to() }))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> crate::test_dir::TestDir {
        crate::test_dir::TestDir::new(&format!("files-{name}"))
    }

    #[test]
    fn a_regular_file_is_read_whole_within_its_limit_and_refused_past_it() {
        let dir = scratch("regular");
        let file = dir.join("a.txt");
        std::fs::write(&file, "hello").unwrap();
        assert_eq!(read_regular_file(&file, 5).unwrap(), b"hello");
        assert_eq!(read_regular_file_to_string(&file, 100).unwrap(), "hello");
        let e = read_regular_file(&file, 4).unwrap_err().to_string();
        assert_eq!(e, format!("{}: 5 bytes, more than vrao's limit of 4", file.display()));
        std::fs::write(&file, b"ok\xff").unwrap();
        let e = read_regular_file_to_string(&file, 100).unwrap_err().to_string();
        assert!(e.ends_with("a.txt: is not UTF-8 text (byte 2)"), "{e}");
        let missing = read_regular_file(&dir.join("none"), 10).unwrap_err();
        assert!(matches!(missing.problem, FileProblem::Missing), "{missing}");
        assert!(missing.to_string().ends_with("none: no such file"));
        let e: Error = missing.into();
        assert!(matches!(e, Error::Input { file: Some(_), .. }));
    }

    #[cfg(unix)]
    #[test]
    fn devices_fifos_folders_and_symlinks_to_them_are_named_without_being_opened() {
        let dir = scratch("special");
        let fifo = dir.join("pipe");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status().is_ok_and(|s| s.success());
        let zero = dir.join("zero.bin");
        std::os::unix::fs::symlink("/dev/zero", &zero).unwrap();
        let started = std::time::Instant::now();
        let mut cases = vec![(zero, "is a character device"), (dir.to_path_buf(), "is a directory")];
        if std::path::Path::new("/dev/urandom").exists() {
            cases.push((PathBuf::from("/dev/urandom"), "is a character device"));
        }
        if made {
            // Opening it would block until a writer came: it must not be opened.
            cases.push((fifo, "is a FIFO (named pipe), not a regular file"));
        }
        for (path, expected) in cases {
            let e = read_regular_file(&path, MAX_FILE_BYTES).unwrap_err().to_string();
            assert!(e.starts_with(&path.display().to_string()) && e.contains(expected), "{e}");
            assert!(read_regular_file_to_string(&path, 10).unwrap_err().to_string().contains(expected));
        }
        assert!(started.elapsed().as_secs() < 2, "refused at once");
    }
}
