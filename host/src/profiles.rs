//! Finding a profile by name: a built-in one (`seed`, `bh8-262-4.3`, `bh8-262-4.4`, the
//! alias `bh8-262`) or a TOML file whose `include`s resolve next to it, then against the
//! embedded `spec/` tree. The model parses; this module only reads files, with the limits of
//! [`crate::files`].

use std::path::Path;
use std::sync::Arc;

use gcl_model::Profile;
use gcl_model::spec::SpecError;

/// Why a profile could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum ProfileError {
    /// Neither a built-in name nor an existing file.
    #[error("unknown profile `{name}`: not a built-in profile ({known}) nor a readable file")]
    Unknown {
        /// The name as given.
        name: String,
        /// The built-in names, `, `-separated.
        known: String,
    },
    /// The profile file itself could not be read (a FIFO, a device, too large...).
    #[error("profile file {name}: {error}")]
    Read {
        /// The name (path) as given.
        name: String,
        /// The reading error (in the message, not a `source`, so that a chain prints it once).
        error: std::io::Error,
    },
    /// A file it includes exists but could not be read.
    #[error("loading profile file {name}: {detail}")]
    Include {
        /// The name (path) as given.
        name: String,
        /// The included file and its reading error.
        detail: String,
    },
    /// A bundle names a profile that is neither built in nor a file inside the bundle.
    #[error(
        "the bundle in {dir} names profile `{name}`, which is neither a built-in profile nor a profile file inside the bundle"
    )]
    NotInBundle {
        /// The name the bundle gives.
        name: String,
        /// The bundle's folder.
        dir: String,
    },
    /// The text is not a valid profile.
    #[error("loading profile file {name}: {error}")]
    Spec {
        /// The name (path) as given.
        name: String,
        /// What the model's loader refused.
        error: SpecError,
    },
}

/// Loads a profile by built-in name or alias, or from a TOML file.
pub fn load(name: &str) -> Result<Arc<Profile>, ProfileError> {
    if let Ok(p) = Profile::builtin(name) {
        return Ok(p);
    }
    let path = Path::new(name);
    if !path.exists() {
        return Err(unknown(name));
    }
    load_file(name, path, false)
}

/// Loads the profile a bundle (a folder written by a fuzzer) names: a built-in profile, or a
/// TOML file directly inside `dir` (`NAME` or `NAME.toml`, a plain file name), whose includes
/// resolve inside `dir` and then against the embedded spec. A bundle is data from anywhere:
/// a path (`/etc/shadow`, `../x`) is refused without being opened.
pub fn load_from_bundle(name: &str, dir: &Path) -> Result<Arc<Profile>, ProfileError> {
    if let Ok(p) = Profile::builtin(name) {
        return Ok(p);
    }
    if !is_plain_name(name) {
        return Err(ProfileError::NotInBundle { name: name.to_string(), dir: dir.display().to_string() });
    }
    let file = [name.to_string(), format!("{name}.toml")].into_iter().map(|f| dir.join(f)).find(|p| p.is_file());
    match file {
        Some(path) => load_file(name, &path, true),
        None => Err(ProfileError::NotInBundle { name: name.to_string(), dir: dir.display().to_string() }),
    }
}

/// A file name with no folder part, not `.` or `..`, and no control characters.
fn is_plain_name(name: &str) -> bool {
    !name.is_empty()
        && name != "."
        && name != ".."
        && !name.contains(['/', '\\'])
        && !name.chars().any(char::is_control)
}

/// A relative path below its folder: no root, no `..`, no control characters.
fn is_confined(path: &str) -> bool {
    let p = Path::new(path);
    !path.is_empty()
        && !path.chars().any(char::is_control)
        && p.components().all(|c| matches!(c, std::path::Component::Normal(_)))
}

fn unknown(name: &str) -> ProfileError {
    ProfileError::Unknown { name: name.to_string(), known: Profile::builtin_names().collect::<Vec<_>>().join(", ") }
}

/// Loads the profile file at `path` (`name` as the user or the bundle gave it); with
/// `confined`, its includes are only looked for below its folder.
fn load_file(name: &str, path: &Path, confined: bool) -> Result<Arc<Profile>, ProfileError> {
    // The file itself first, so a FIFO, a device or a huge file is one clear error.
    let top_text =
        crate::files::read_input_text(path).map_err(|error| ProfileError::Read { name: name.to_string(), error })?;
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let top = path.file_name().and_then(|f| f.to_str()).unwrap_or_default().to_string();
    let failed = std::cell::RefCell::new(None::<String>);
    let resolve = |f: &str| -> Option<String> {
        if f == top {
            return Some(top_text.clone());
        }
        if confined && !is_confined(f) {
            failed.borrow_mut().get_or_insert_with(|| format!("include `{f}`: not a file inside the bundle"));
            return None;
        }
        let p = dir.join(f);
        match crate::files::read_input_text(&p) {
            Ok(t) => Some(t),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => gcl_model::spec::embedded(f).map(str::to_string),
            Err(e) => {
                failed.borrow_mut().get_or_insert_with(|| format!("{}: {e}", p.display()));
                None
            }
        }
    };
    let loaded = Profile::load_with(&top, &resolve);
    if let Some(detail) = failed.into_inner() {
        return Err(ProfileError::Include { name: name.to_string(), detail });
    }
    let p = loaded.map_err(|error| ProfileError::Spec { name: name.to_string(), error })?;
    Ok(Arc::new(p))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 20 item 14: a bundle's profile is a built-in one or a file inside the bundle; a
    /// path anywhere else is refused without being read, and no error quotes a file that is
    /// not a profile.
    #[test]
    fn a_bundle_names_a_builtin_profile_or_a_file_inside_it() {
        let dir = tempfile::tempdir().unwrap();
        let secret = dir.path().join("secret");
        std::fs::write(&secret, "root:$6$secretsalt$hash:19000:0:99999:7:::\n").unwrap();
        let bundle = dir.path().join("bundle");
        std::fs::create_dir(&bundle).unwrap();
        assert_eq!(load_from_bundle("seed", &bundle).unwrap().id, "seed");
        for bad in [secret.to_str().unwrap(), "../secret", "/etc/shadow", "."] {
            let e = load_from_bundle(bad, &bundle).unwrap_err().to_string();
            assert!(e.contains("neither a built-in profile nor a profile file inside"), "{bad}: {e}");
            assert!(!e.contains("secretsalt"), "{e}");
        }
        // A file inside the bundle that is no profile: refused, its text not quoted.
        std::fs::copy(&secret, bundle.join("mine.toml")).unwrap();
        let e = load_from_bundle("mine", &bundle).unwrap_err().to_string();
        assert!(e.contains("mine") && !e.contains("secretsalt") && !e.contains("root"), "{e}");
        // A profile file inside the bundle loads; its includes stay inside the bundle.
        std::fs::write(bundle.join("mine.toml"), "include = [\"seed.toml\"]\nid = \"mine\"\n").unwrap();
        assert_eq!(load_from_bundle("mine", &bundle).unwrap().id, "mine");
        std::fs::write(bundle.join("mine.toml"), format!("include = [\"{}\"]\n", secret.display())).unwrap();
        let e = load_from_bundle("mine", &bundle).unwrap_err().to_string();
        assert!(e.contains("not a file inside the bundle") && !e.contains("secretsalt"), "{e}");
    }
}
