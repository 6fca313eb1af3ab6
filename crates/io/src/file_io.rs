//! Reading untrusted input files and writing every output file: the one place where keyrig
//! opens files (docs/design.md §8).
//!
//! **Reading** ([`open_regular_file`], [`read_regular_file`]): the file must be a regular
//! file (not a FIFO, a device such as `/dev/zero`, a socket or a folder) and no larger than
//! a stated limit ([`MAX_MODEL_BYTES`], [`MAX_MD2_BYTES`], [`MAX_SCENE_BYTES`]). Both are
//! checked on the opened file (`fstat`) before a byte is read; on Unix the file is opened
//! with `O_NONBLOCK`, so that opening a FIFO never waits for a writer. The read itself stops
//! at the limit, so a file that grows while it is read cannot exceed it either.
//!
//! **Writing** ([`AtomicFile`], [`write_atomic`], [`write_atomic_with`]): the bytes go to a
//! fresh temporary file `.<name>.tmp-<pid>-<n>` in the target's folder, which is flushed and
//! synced and then renamed over the target; the folder is synced after the rename. The target
//! therefore always holds either its previous content or the complete new content, whatever
//! happens during the write (an error, a full disk, the process killed). On any error the
//! temporary file is removed. Scene saves also keep the previous file as `<name>.bak`
//! ([`AtomicFile::keep_backup`]).
//!
//! **Refusing to overwrite inputs** ([`refuse_overwriting`]): a command passes its output
//! and its inputs (the file it read, model files a scene references, an MD2 skin image);
//! an output that is one of them (the same path, or the same file through another path or a
//! hard link) is refused before anything is written.

use std::fs;
use std::io::{self, Read, Write};
use std::path::{Path, PathBuf};

/// Largest glTF file (.glb, .gltf) or external glTF buffer keyrig reads: 1 GiB.
pub const MAX_MODEL_BYTES: u64 = 1 << 30;
/// Largest MD2 file keyrig reads: 64 MiB. Quake 2's own limits (2048 vertices, 512 frames,
/// 4096 triangles) make a real model at most about 5 MB.
pub const MAX_MD2_BYTES: u64 = 64 << 20;
/// Largest scene file (.ron) keyrig reads: 256 MiB.
pub const MAX_SCENE_BYTES: u64 = 256 << 20;

/// What kind of file system object `meta` describes, for error messages.
fn kind_of(meta: &fs::Metadata) -> &'static str {
    let ft = meta.file_type();
    if ft.is_dir() {
        return "a folder";
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if ft.is_fifo() {
            return "a FIFO (named pipe)";
        }
        if ft.is_char_device() {
            return "a character device";
        }
        if ft.is_block_device() {
            return "a block device";
        }
        if ft.is_socket() {
            return "a socket";
        }
    }
    "not a regular file"
}

fn not_regular(meta: &fs::Metadata) -> io::Error {
    io::Error::new(
        io::ErrorKind::InvalidInput,
        format!("{} is not a regular file; keyrig reads only regular files", kind_of(meta)),
    )
}

fn too_large(len: u64, limit: u64) -> io::Error {
    io::Error::new(
        io::ErrorKind::InvalidData,
        format!("the file is {len} bytes, more than the limit of {limit} bytes ({} MiB)", limit >> 20),
    )
}

/// Opens `path` for reading after checking that it is a regular file of at most
/// `max_bytes` bytes; returns the file and its length. Never blocks on a FIFO.
///
/// # Errors
/// The file cannot be opened, is not a regular file, or is larger than `max_bytes`.
pub fn open_regular_file(path: &Path, max_bytes: u64) -> io::Result<(fs::File, u64)> {
    // Look before opening: opening a FIFO for reading would wait for a writer, and opening a
    // folder succeeds on Unix.
    let meta = fs::metadata(path)?;
    if !meta.is_file() {
        return Err(not_regular(&meta));
    }
    let mut options = fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        // Should the path be swapped for a FIFO between the check and the open, the open
        // still returns at once; the check on the opened file below then refuses it.
        options.custom_flags(libc::O_NONBLOCK);
    }
    let file = options.open(path)?;
    let meta = file.metadata()?;
    if !meta.is_file() {
        return Err(not_regular(&meta));
    }
    if meta.len() > max_bytes {
        return Err(too_large(meta.len(), max_bytes));
    }
    Ok((file, meta.len()))
}

/// Reads the whole regular file `path` of at most `max_bytes` bytes (see
/// [`open_regular_file`]).
///
/// # Errors
/// As [`open_regular_file`], or a read error, or the file grew past `max_bytes` while it was
/// read.
pub fn read_regular_file(path: &Path, max_bytes: u64) -> io::Result<Vec<u8>> {
    let (file, len) = open_regular_file(path, max_bytes)?;
    read_capped(file, len, max_bytes)
}

/// Reads `reader` to its end, refusing more than `max_bytes` bytes; `len_hint` (the length
/// the file had when it was opened) only sizes the first allocation.
///
/// # Errors
/// A read error, or more than `max_bytes` bytes.
pub fn read_capped(reader: impl Read, len_hint: u64, max_bytes: u64) -> io::Result<Vec<u8>> {
    let capacity = usize::try_from(len_hint.min(max_bytes)).unwrap_or(0);
    let mut data = Vec::with_capacity(capacity);
    reader.take(max_bytes.saturating_add(1)).read_to_end(&mut data)?;
    if data.len() as u64 > max_bytes {
        return Err(too_large(data.len() as u64, max_bytes));
    }
    Ok(data)
}

/// A new file that replaces `target` only when [`AtomicFile::commit`] succeeds.
///
/// Write to it with [`std::io::Write`]; dropping it without committing removes the temporary
/// file and leaves `target` untouched.
#[derive(Debug)]
pub struct AtomicFile {
    target: PathBuf,
    dir: PathBuf,
    tmp_path: PathBuf,
    file: Option<io::BufWriter<fs::File>>,
    keep_backup: bool,
}

impl AtomicFile {
    /// Creates the temporary file beside `target` (in `.` for a bare file name).
    ///
    /// # Errors
    /// `target` has no file name, names a folder, or the temporary file cannot be created.
    pub fn create(target: &Path) -> io::Result<AtomicFile> {
        let name = target
            .file_name()
            .ok_or_else(|| io::Error::new(io::ErrorKind::InvalidInput, "the path has no file name"))?;
        if fs::metadata(target).is_ok_and(|m| m.is_dir()) {
            return Err(io::Error::new(io::ErrorKind::InvalidInput, "the path is a folder"));
        }
        let dir = parent_or_dot(target);
        let (tmp_path, file) = create_temp(&dir, &name.to_string_lossy())?;
        Ok(AtomicFile {
            target: target.to_path_buf(),
            dir,
            tmp_path,
            file: Some(io::BufWriter::new(file)),
            keep_backup: false,
        })
    }

    /// Keep the previous `target` as `<name>.bak` when committing (scene files).
    #[must_use]
    pub fn keep_backup(mut self, keep: bool) -> AtomicFile {
        self.keep_backup = keep;
        self
    }

    /// Flushes and syncs the temporary file, keeps the backup when asked, renames the
    /// temporary file over the target and syncs the folder.
    ///
    /// # Errors
    /// Any step fails; the temporary file is then removed and the target is untouched.
    pub fn commit(mut self) -> io::Result<()> {
        let result = self.finish();
        if result.is_err() {
            let _ = fs::remove_file(&self.tmp_path);
        }
        // Nothing left for Drop to clean up: the file is renamed or already removed.
        self.file = None;
        result
    }

    fn finish(&mut self) -> io::Result<()> {
        let writer = self.file.take().ok_or_else(|| io::Error::other("already committed"))?;
        let file = writer.into_inner().map_err(io::IntoInnerError::into_error)?;
        file.sync_all()?;
        drop(file);
        if self.keep_backup && fs::symlink_metadata(&self.target).is_ok() {
            keep_backup(&self.target).map_err(|e| {
                let bak = backup_path(&self.target);
                io::Error::new(e.kind(), format!("cannot keep the previous file as {}: {e}", bak.display()))
            })?;
        }
        fs::rename(&self.tmp_path, &self.target)?;
        sync_dir(&self.dir);
        Ok(())
    }
}

impl Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        match &mut self.file {
            Some(f) => f.write(buf),
            None => Err(io::Error::other("already committed")),
        }
    }

    fn flush(&mut self) -> io::Result<()> {
        match &mut self.file {
            Some(f) => f.flush(),
            None => Ok(()),
        }
    }
}

/// Seeking (after flushing what is buffered) lets writers that patch a header once the body is
/// written, such as an MP4 muxer, write atomically too.
impl io::Seek for AtomicFile {
    fn seek(&mut self, pos: io::SeekFrom) -> io::Result<u64> {
        match &mut self.file {
            Some(f) => io::Seek::seek(f, pos),
            None => Err(io::Error::other("already committed")),
        }
    }
}

/// Reading back what is written (after flushing what is buffered) lets writers that finish a
/// file by rewriting a part of it, such as the MP4 muxer's sound track, do so atomically too.
impl io::Read for AtomicFile {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        match &mut self.file {
            Some(f) => {
                f.flush()?;
                f.get_mut().read(buf)
            }
            None => Err(io::Error::other("already committed")),
        }
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        if self.file.take().is_some() {
            let _ = fs::remove_file(&self.tmp_path);
        }
    }
}

/// Writes `bytes` to `path` atomically (see the module documentation).
///
/// # Errors
/// The temporary file cannot be created, written, synced or renamed; `path` then keeps its
/// previous content and no temporary file is left.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> io::Result<()> {
    write_atomic_with(path, |w| w.write_all(bytes))
}

/// Writes to `path` atomically whatever `fill` writes; an error from `fill` abandons the
/// write (the target keeps its previous content).
///
/// # Errors
/// `fill` fails, or the temporary file cannot be created, synced or renamed.
pub fn write_atomic_with(path: &Path, fill: impl FnOnce(&mut dyn Write) -> io::Result<()>) -> io::Result<()> {
    let mut file = AtomicFile::create(path)?;
    fill(&mut file)?;
    file.commit()
}

/// The backup path of a file: `<name>.bak` beside it.
#[must_use]
pub fn backup_path(path: &Path) -> PathBuf {
    let mut name = path.file_name().map(|n| n.to_os_string()).unwrap_or_default();
    name.push(".bak");
    path.with_file_name(name)
}

/// The folder of `path`; `.` for a bare file name (whose parent is the empty path).
#[must_use]
pub fn parent_or_dot(path: &Path) -> PathBuf {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// Creates `.<name>.tmp-<pid>-<n>` in `dir` with `create_new`, so that it never replaces
/// anything.
fn create_temp(dir: &Path, name: &str) -> io::Result<(PathBuf, fs::File)> {
    let pid = std::process::id();
    for n in 0..1000u32 {
        let candidate = dir.join(format!(".{name}.tmp-{pid}-{n}"));
        match fs::OpenOptions::new().read(true).write(true).create_new(true).open(&candidate) {
            Ok(file) => return Ok((candidate, file)),
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(e),
        }
    }
    Err(io::Error::new(io::ErrorKind::AlreadyExists, "no free temporary file name"))
}

/// Makes `<name>.bak` hold the current content of `path` (a hard link when the file system
/// allows it, a copy otherwise). The old backup is replaced.
fn keep_backup(path: &Path) -> io::Result<()> {
    let bak = backup_path(path);
    match fs::remove_file(&bak) {
        Ok(()) => {}
        Err(e) if e.kind() == io::ErrorKind::NotFound => {}
        Err(e) => return Err(e),
    }
    if fs::hard_link(path, &bak).is_err() {
        fs::copy(path, &bak)?;
    }
    Ok(())
}

/// Syncs the folder so that the rename survives a crash (where the platform allows).
fn sync_dir(dir: &Path) {
    #[cfg(unix)]
    if let Ok(d) = fs::File::open(dir) {
        // A failure here does not undo the write; the data itself is already synced.
        let _ = d.sync_all();
    }
    #[cfg(not(unix))]
    let _ = dir;
}

/// A command's output would replace one of its inputs.
#[derive(Debug, thiserror::Error)]
#[error("{}: refusing to overwrite {what} ({}); choose another output file", output.display(), input.display())]
pub struct OverwriteInputError {
    pub output: PathBuf,
    pub input: PathBuf,
    /// What the input is, e.g. "the input file" or "the model file objects[0] (`Arm`) uses".
    pub what: String,
}

/// Whether `a` and `b` name the same file: the same file on disk when both exist (same
/// device and inode on Unix, so hard links and symbolic links count), else the same
/// absolute path after resolving the folders that exist.
#[must_use]
pub fn same_file(a: &Path, b: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if let (Ok(ma), Ok(mb)) = (fs::metadata(a), fs::metadata(b)) {
            return ma.dev() == mb.dev() && ma.ino() == mb.ino();
        }
    }
    resolved(a) == resolved(b)
}

/// `path` made absolute, with its longest existing prefix canonicalized.
fn resolved(path: &Path) -> PathBuf {
    if let Ok(p) = fs::canonicalize(path) {
        return p;
    }
    let absolute = if path.is_absolute() {
        path.to_path_buf()
    } else {
        std::env::current_dir().map(|d| d.join(path)).unwrap_or_else(|_| path.to_path_buf())
    };
    match (absolute.parent(), absolute.file_name()) {
        (Some(parent), Some(name)) => resolved(parent).join(name),
        _ => absolute,
    }
}

/// Refuses `output` when it is one of `inputs` (each with a description of what it is).
///
/// # Errors
/// [`OverwriteInputError`] naming the first input `output` would replace.
pub fn refuse_overwriting(output: &Path, inputs: &[(PathBuf, String)]) -> Result<(), OverwriteInputError> {
    for (input, what) in inputs {
        if same_file(output, input) {
            return Err(OverwriteInputError {
                output: output.to_path_buf(),
                input: input.clone(),
                what: what.clone(),
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Seek as _;

    #[test]
    fn a_failed_write_leaves_the_previous_file_and_no_temporary_file() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("out.glb");
        fs::write(&path, b"previous content").expect("write");
        let err = write_atomic_with(&path, |w| {
            w.write_all(&[7u8; 100_000])?;
            Err(io::Error::new(io::ErrorKind::StorageFull, "injected: no space left on device"))
        })
        .expect_err("the injected error");
        assert!(err.to_string().contains("injected"), "{err}");
        assert_eq!(fs::read(&path).expect("read"), b"previous content");
        let left: Vec<_> =
            fs::read_dir(dir.path()).expect("dir").map(|e| e.expect("entry").file_name()).collect();
        assert_eq!(left, vec![std::ffi::OsString::from("out.glb")], "temporary file left behind");
    }

    #[test]
    fn a_committed_write_replaces_the_file_and_keeps_a_backup_when_asked() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("scene.ron");
        write_atomic(&path, b"one").expect("first");
        assert_eq!(fs::read(&path).expect("read"), b"one");
        let mut f = AtomicFile::create(&path).expect("create").keep_backup(true);
        f.write_all(b"two").expect("write");
        f.commit().expect("commit");
        assert_eq!(fs::read(&path).expect("read"), b"two");
        assert_eq!(fs::read(backup_path(&path)).expect("backup"), b"one");
    }

    #[test]
    fn a_seeking_writer_patches_what_it_wrote() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("movie.mp4");
        let mut f = AtomicFile::create(&path).expect("create");
        f.write_all(b"size????body").expect("write");
        f.seek(io::SeekFrom::Start(4)).expect("seek");
        f.write_all(b"0012").expect("patch");
        assert_eq!(f.seek(io::SeekFrom::End(0)).expect("end"), 12);
        f.commit().expect("commit");
        assert_eq!(fs::read(&path).expect("read"), b"size0012body");
    }

    #[test]
    fn dropping_without_commit_removes_the_temporary_file() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("a.png");
        let mut f = AtomicFile::create(&path).expect("create");
        f.write_all(b"partial").expect("write");
        let tmp = f.tmp_path.clone();
        assert!(tmp.exists());
        drop(f);
        assert!(!tmp.exists() && !path.exists());
    }

    #[test]
    fn non_regular_and_oversized_files_are_refused_before_reading() {
        let dir = tempfile::tempdir().expect("tempdir");
        let err = read_regular_file(dir.path(), 100).expect_err("a folder");
        assert!(err.to_string().contains("a folder"), "{err}");
        #[cfg(unix)]
        {
            let err = read_regular_file(Path::new("/dev/zero"), 100).expect_err("a device");
            assert!(err.to_string().contains("character device"), "{err}");
        }
        let big = dir.path().join("big.bin");
        fs::write(&big, vec![0u8; 1000]).expect("write");
        let err = read_regular_file(&big, 999).expect_err("too large");
        assert!(err.to_string().contains("1000 bytes") && err.to_string().contains("999"), "{err}");
        assert_eq!(read_regular_file(&big, 1000).expect("at the limit").len(), 1000);
        let err = read_capped(&[1u8; 10][..], 0, 9).expect_err("grew past the limit");
        assert!(err.to_string().contains("limit"), "{err}");
    }

    #[test]
    fn outputs_that_are_inputs_are_refused() {
        let dir = tempfile::tempdir().expect("tempdir");
        let input = dir.path().join("model.glb");
        fs::write(&input, b"x").expect("write");
        let inputs = vec![(input.clone(), "the input file".to_owned())];
        let dotted = dir.path().join(".").join("model.glb");
        let err = refuse_overwriting(&dotted, &inputs).expect_err("same file");
        assert!(err.to_string().contains("refusing to overwrite the input file"), "{err}");
        let link = dir.path().join("link.glb");
        fs::hard_link(&input, &link).expect("link");
        assert!(refuse_overwriting(&link, &inputs).is_err(), "a hard link is the same file");
        assert!(refuse_overwriting(&dir.path().join("other.glb"), &inputs).is_ok());
    }
}
