//! Scratch directories for tests (this crate's, the application's and its integration
//! tests'): one per test, removed when the test ends, kept and named when it fails (its
//! files are the evidence). Tests that made their own and never removed them left
//! gigabytes under the temp dir over a few hundred runs.

use std::path::{Path, PathBuf};

/// A fresh, empty directory `vrao-test-PID-NAME` under the system's temp dir, removed
/// when dropped unless the thread is panicking.
pub struct TestDir(PathBuf);

impl TestDir {
    /// Makes the directory `name` (empty, whatever was there before).
    ///
    /// # Panics
    /// When the directory cannot be made: a test cannot run without it.
    pub fn new(name: &str) -> TestDir {
        let dir = std::env::temp_dir().join(format!("vrao-test-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
        TestDir(dir)
    }

    /// Writes `contents` to `name` in the directory; returns its path.
    ///
    /// # Panics
    /// When the file cannot be written.
    pub fn write(&self, name: &str, contents: impl AsRef<[u8]>) -> PathBuf {
        let path = self.0.join(name);
        std::fs::write(&path, contents).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        path
    }
}

impl std::ops::Deref for TestDir {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<Path> for TestDir {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<std::ffi::OsStr> for TestDir {
    fn as_ref(&self) -> &std::ffi::OsStr {
        self.0.as_os_str()
    }
}

impl Drop for TestDir {
    fn drop(&mut self) {
        if std::thread::panicking() {
            eprintln!("kept the failing test's files in {}", self.0.display());
        } else {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}
