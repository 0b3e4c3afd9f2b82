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
        return Err(ProfileError::Unknown {
            name: name.to_string(),
            known: Profile::builtin_names().collect::<Vec<_>>().join(", "),
        });
    }
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
