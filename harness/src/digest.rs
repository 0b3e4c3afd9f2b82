//! Digests as the project spells them: SHA-256 in lower-case hex, for certificates and their
//! manifests, suite and profile versions, and the names of findings and corpus entries.

use sha2::{Digest, Sha256};

/// SHA-256 of bytes, lower-case hex.
pub fn sha256_hex(bytes: &[u8]) -> String {
    hex(&Sha256::digest(bytes))
}

/// Bytes as lower-case hex (a digest's usual spelling).
pub fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}
