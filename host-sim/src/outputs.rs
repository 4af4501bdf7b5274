//! Files a command writes: all or nothing, and never over its inputs.
//!
//! A command names its inputs and its outputs before it does any work.
//! [`Outputs::output`] refuses an output that is one of the inputs (the
//! same path, a symlink to it, a hard link: the same device and inode) or
//! another output, and creates a temporary file beside it, which proves
//! that the folder takes a file. The work writes into the temporaries;
//! [`Outputs::commit`] renames them all into place at the end. If the work
//! fails (or the command returns early), dropping `Outputs` removes every
//! temporary: no output is left half-written and none is left behind.
//!
//! ```
//! use terracast_sim::outputs::Outputs;
//! let dir = tempfile::tempdir().unwrap();
//! let (input, out) = (dir.path().join("in.txt"), dir.path().join("out.txt"));
//! std::fs::write(&input, "heights").unwrap();
//!
//! let mut outputs = Outputs::new();
//! outputs.input("--height", &input);
//! // Writing over the input is refused before anything is opened.
//! assert!(outputs.output("--out", &input).is_err());
//! let out_id = outputs.output("--out", &out).unwrap();
//! std::fs::write(outputs.temporary(out_id), "image").unwrap();
//! assert!(!out.exists(), "nothing is in place before the commit");
//! outputs.commit().unwrap();
//! assert_eq!(std::fs::read_to_string(&out).unwrap(), "image");
//! ```

use crate::error::{Error, Result};
use std::path::{Path, PathBuf};
use tempfile::NamedTempFile;

/// Which output of an [`Outputs`] set: the index `output` returned.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct OutputId(usize);

/// The inputs and pending outputs of one command.
#[derive(Debug, Default)]
pub struct Outputs {
    inputs: Vec<(String, PathBuf)>,
    pending: Vec<Pending>,
}

#[derive(Debug)]
struct Pending {
    flag: String,
    path: PathBuf,
    temporary: NamedTempFile,
}

impl Outputs {
    /// No inputs and no outputs yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// Names a file the command reads (`flag` names it in messages). A
    /// path that does not exist is kept too: nothing can alias it.
    pub fn input(&mut self, flag: &str, path: &Path) {
        self.inputs.push((flag.to_owned(), path.to_owned()));
    }

    /// Names a file the command writes, and creates its temporary beside
    /// it. Refuses a path that is an input or an output already named, and
    /// a folder that does not exist or takes no file.
    pub fn output(&mut self, flag: &str, path: &Path) -> Result<OutputId> {
        self.check_not_an_input(flag, path)?;
        if let Some(other) = self
            .pending
            .iter()
            .find(|p| same_destination(&p.path, path))
        {
            return Err(Error::new(format!(
                "{flag} {} is also the output {}: give each output its own file",
                path.display(),
                other.flag
            )));
        }
        if path.is_dir() {
            return Err(Error::new(format!(
                "{flag} {}: is a folder, not a file",
                path.display()
            )));
        }
        let temporary = temporary_beside(flag, path)?;
        self.pending.push(Pending {
            flag: flag.to_owned(),
            path: path.to_owned(),
            temporary,
        });
        Ok(OutputId(self.pending.len() - 1))
    }

    /// Checks that `dir` is an existing folder that takes files, for an
    /// output that writes many files into it (each then named with
    /// [`Outputs::output`] as it is written).
    pub fn folder(&self, flag: &str, dir: &Path) -> Result<()> {
        if !dir.is_dir() {
            return Err(Error::new(format!(
                "{flag} {}: no such folder",
                dir.display()
            )));
        }
        temporary_beside(flag, &dir.join("probe")).map(drop)
    }

    /// The temporary file that output `id` is written to until the commit.
    /// It carries the destination's extension, so that writers that pick a
    /// format by extension pick the right one.
    pub fn temporary(&self, id: OutputId) -> &Path {
        self.pending[id.0].temporary.path()
    }

    /// Renames every temporary into place. If a rename fails, the outputs
    /// already in place are removed again and the rest are dropped, so the
    /// command leaves none of them.
    pub fn commit(self) -> Result<()> {
        let mut placed: Vec<PathBuf> = Vec::with_capacity(self.pending.len());
        for pending in self.pending {
            let Pending {
                flag,
                path,
                temporary,
            } = pending;
            if let Err(e) = temporary.persist(&path) {
                for done in &placed {
                    let _ = std::fs::remove_file(done);
                }
                return Err(Error::new(format!(
                    "cannot write {flag} {}: {}",
                    path.display(),
                    e.error
                )));
            }
            placed.push(path);
        }
        Ok(())
    }

    fn check_not_an_input(&self, flag: &str, path: &Path) -> Result<()> {
        for (input_flag, input) in &self.inputs {
            let aliased = same_destination(input, path)
                || same_file::is_same_file(input, path).unwrap_or(false);
            if aliased {
                return Err(Error::new(format!(
                    "{flag} {} is the input {input_flag} {}: writing it would destroy the input; choose another output",
                    path.display(),
                    input.display()
                )));
            }
        }
        Ok(())
    }
}

/// A temporary file in `path`'s folder, named after it.
fn temporary_beside(flag: &str, path: &Path) -> Result<NamedTempFile> {
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    if !dir.is_dir() {
        return Err(Error::new(format!(
            "cannot write {flag} {}: folder {} does not exist",
            path.display(),
            dir.display()
        )));
    }
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let suffix = path
        .extension()
        .map(|e| format!(".{}", e.to_string_lossy()))
        .unwrap_or_default();
    let prefix = format!(".{stem}.");
    let mut builder = tempfile::Builder::new();
    builder.prefix(&prefix).suffix(&suffix);
    // An output gets the permissions a plain create would give it (the
    // umask applies), not a temporary file's private ones.
    #[cfg(unix)]
    builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
    builder
        .tempfile_in(dir)
        .map_err(|e| Error::new(format!("cannot write {flag} {}: {e}", path.display())))
}

/// Whether two paths name the same directory entry, whether or not it
/// exists yet: the same file name in the same (resolved) folder.
fn same_destination(a: &Path, b: &Path) -> bool {
    let resolved = |p: &Path| -> Option<PathBuf> {
        let dir = p
            .parent()
            .filter(|d| !d.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        Some(dir.canonicalize().ok()?.join(p.file_name()?))
    };
    match (resolved(a), resolved(b)) {
        (Some(a), Some(b)) => a == b,
        _ => a == b,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_output_that_aliases_an_input_is_refused_and_the_input_kept() {
        let dir = tempfile::tempdir().unwrap();
        let input = dir.path().join("heights.png");
        std::fs::write(&input, b"input bytes").unwrap();
        let symlink = dir.path().join("link.png");
        std::os::unix::fs::symlink(&input, &symlink).unwrap();
        let hard_link = dir.path().join("hard.png");
        std::fs::hard_link(&input, &hard_link).unwrap();
        let dotted = dir.path().join(".").join("heights.png");
        for alias in [&input, &symlink, &hard_link, &dotted] {
            let mut outputs = Outputs::new();
            outputs.input("--height", &input);
            let message = outputs.output("--out", alias).unwrap_err().to_string();
            assert!(
                message.contains("--out") && message.contains("--height"),
                "{message}"
            );
            drop(outputs);
        }
        assert_eq!(std::fs::read(&input).unwrap(), b"input bytes");
        let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(left.len(), 3, "no temporary is left behind");
    }

    #[test]
    fn the_same_output_twice_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let mut outputs = Outputs::new();
        outputs.output("--out", &dir.path().join("a.png")).unwrap();
        let message = outputs
            .output("--depth", &dir.path().join("a.png"))
            .unwrap_err()
            .to_string();
        assert!(message.contains("--depth") && message.contains("--out"));
    }

    #[test]
    fn an_uncommitted_set_leaves_nothing_and_a_committed_one_everything() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (dir.path().join("a.json"), dir.path().join("b.png"));
        let mut outputs = Outputs::new();
        let ids = [
            outputs.output("--stats", &a).unwrap(),
            outputs.output("--out", &b).unwrap(),
        ];
        for id in ids {
            assert_eq!(outputs.temporary(id).parent(), Some(dir.path()));
            std::fs::write(outputs.temporary(id), b"x").unwrap();
        }
        assert_eq!(
            outputs.temporary(ids[1]).extension(),
            Some("png".as_ref()),
            "the temporary keeps the destination's extension"
        );
        drop(outputs);
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);

        let mut outputs = Outputs::new();
        let id = outputs.output("--stats", &a).unwrap();
        std::fs::write(outputs.temporary(id), b"x").unwrap();
        outputs.commit().unwrap();
        assert_eq!(std::fs::read(&a).unwrap(), b"x");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[test]
    fn a_missing_folder_is_refused_before_any_work() {
        let dir = tempfile::tempdir().unwrap();
        let mut outputs = Outputs::new();
        let message = outputs
            .output("--report", &dir.path().join("no/such/r.json"))
            .unwrap_err()
            .to_string();
        assert!(message.contains("--report") && message.contains("does not exist"));
        assert!(outputs
            .folder("--frames-dir", &dir.path().join("none"))
            .is_err());
        outputs.folder("--frames-dir", dir.path()).unwrap();
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }
}
