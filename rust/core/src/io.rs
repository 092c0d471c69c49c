//! File output that never leaves a half-written file.
//!
//! Entry points: [`write_atomic`] — write to a temporary file in the target's directory,
//! flush it to disk, rename it over the target, flush the directory; [`read_bounded`] —
//! read a file of at most a given size (endless inputs such as `/dev/zero` are an error).

use std::io::{Read, Write};
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};

use crate::error::{Error, Result};

/// Write `bytes` to `path` atomically: a temporary sibling file (same directory, so the
/// rename cannot cross file systems) is created exclusively, written, synced, and renamed
/// over `path`; then the directory is synced so that the rename itself survives a power
/// cut. A reader, or a process killed at any moment (SIGKILL included), sees the old file or
/// the new one, never a mix. On error the temporary file is removed and `path` is untouched.
///
/// An existing target that is not a regular file or a directory (`/dev/null`, `/dev/stdout`,
/// a named pipe) is written in place: renaming over it would replace the device itself.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    if let Ok(meta) = std::fs::metadata(path) {
        if !meta.is_file() && !meta.is_dir() {
            let mut f = std::fs::OpenOptions::new()
                .write(true)
                .open(path)
                .map_err(|e| Error::io(path, e))?;
            return f.write_all(bytes).map_err(|e| Error::io(path, e));
        }
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => std::path::PathBuf::from("."),
    };
    let file_name = path
        .file_name()
        .ok_or_else(|| Error::argument("path", path.display(), "names no file"))?;
    // Unique per process and per call: two threads (or two writers) never share a temp file.
    let tmp = dir.join(format!(
        ".{}.tmp-{}-{}",
        file_name.to_string_lossy(),
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    let result = (|| {
        let mut f = std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        drop(f);
        std::fs::rename(&tmp, path)
    })();
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(Error::io(path, e));
    }
    sync_dir(&dir);
    Ok(())
}

/// Flush a directory's entries (the rename) to disk. Best effort: some file systems refuse
/// to open or sync a directory, and the data itself is already synced.
fn sync_dir(dir: &Path) {
    #[cfg(unix)]
    if let Ok(d) = std::fs::File::open(dir) {
        let _ = d.sync_all();
    }
    #[cfg(not(unix))]
    let _ = dir;
}

/// Read at most `max_bytes` of `path`; a longer file (or an endless one such as
/// `/dev/zero`) is an [`Error::Io`] of kind `InvalidData` naming the limit, read no further.
pub fn read_bounded(path: &Path, max_bytes: u64) -> Result<Vec<u8>> {
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let mut bytes = Vec::new();
    file.take(max_bytes + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| Error::io(path, e))?;
    if bytes.len() as u64 > max_bytes {
        return Err(Error::io(
            path,
            std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                format!("file is larger than {max_bytes} bytes"),
            ),
        ));
    }
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_and_replaces() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("out.json");
        write_atomic(&p, b"one").unwrap();
        write_atomic(&p, b"two").unwrap();
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "two");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[test]
    fn missing_directory_is_an_io_error_and_leaves_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("no/such/dir/out.json");
        let e = write_atomic(&p, b"x").unwrap_err();
        assert!(matches!(e, Error::Io { .. }), "{e}");
        assert!(e.to_string().contains("out.json"));
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }

    #[test]
    fn failed_rename_removes_the_temp_file() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("a_directory");
        std::fs::create_dir(&target).unwrap();
        std::fs::write(target.join("inside"), b"x").unwrap();
        let e = write_atomic(&target, b"new").unwrap_err();
        assert!(matches!(e, Error::Io { .. }), "{e}");
        let names: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, vec![std::ffi::OsString::from("a_directory")]);
    }

    #[cfg(unix)]
    #[test]
    fn a_device_is_written_in_place_not_replaced() {
        write_atomic(Path::new("/dev/null"), b"discarded").unwrap();
        let meta = std::fs::metadata("/dev/null").unwrap();
        assert!(!meta.is_file(), "/dev/null must stay a device");
    }

    #[cfg(unix)]
    #[test]
    fn endless_input_is_an_error_not_an_exhausted_memory() {
        let e = read_bounded(Path::new("/dev/zero"), 1 << 20).unwrap_err();
        assert!(e.to_string().contains("larger than 1048576 bytes"), "{e}");
    }

    #[test]
    fn bounded_read_takes_a_file_of_exactly_the_limit() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("f");
        std::fs::write(&p, b"12345").unwrap();
        assert_eq!(read_bounded(&p, 5).unwrap(), b"12345");
        assert!(read_bounded(&p, 4).is_err());
    }

    /// A reader polling the target while it is rewritten sees a whole old or a whole new
    /// file, never a mix or a short one (a truncate-and-write fails this at once).
    #[test]
    fn a_concurrent_reader_never_sees_a_partial_file() {
        use std::sync::atomic::AtomicBool;
        use std::sync::Arc;
        const N: usize = 1 << 20;
        let dir = tempfile::tempdir().unwrap();
        let p = Arc::new(dir.path().join("big.bin"));
        write_atomic(&p, &vec![b'a'; N]).unwrap();
        let done = Arc::new(AtomicBool::new(false));
        let reader = {
            let (p, done) = (Arc::clone(&p), Arc::clone(&done));
            std::thread::spawn(move || {
                let mut reads = 0u32;
                while !done.load(Ordering::Relaxed) {
                    let b = std::fs::read(&*p).unwrap();
                    assert_eq!(b.len(), N, "a short file was visible");
                    assert!(b.iter().all(|&x| x == b[0]), "a mixed file was visible");
                    reads += 1;
                }
                reads
            })
        };
        for i in 0..24 {
            write_atomic(&p, &vec![if i % 2 == 0 { b'b' } else { b'a' }; N]).unwrap();
        }
        done.store(true, Ordering::Relaxed);
        assert!(reader.join().unwrap() > 0);
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }
}
