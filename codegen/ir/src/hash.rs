//! The content hash: SHA-256 of the file's bytes with the hash value replaced by the placeholder
//! `"sha256:"` + 64 zeros (the writer hashes the text with the placeholder, then writes the hash
//! over the first occurrence of the placeholder).

use sha2::{Digest, Sha256};

use crate::error::Problem;

/// The placeholder the hash is computed with.
pub const HASH_PLACEHOLDER: &str =
    "sha256:0000000000000000000000000000000000000000000000000000000000000000";

/// `sha256:<hex>` of a text that holds the placeholder where the hash goes.
pub fn sha256_hex(text: &str) -> String {
    sha256_hex_bytes(text.as_bytes())
}

/// `sha256:<hex>` of bytes.
pub fn sha256_hex_bytes(bytes: &[u8]) -> String {
    let digest = Sha256::digest(bytes);
    let hex: String = digest.iter().map(|b| format!("{b:02x}")).collect();
    format!("sha256:{hex}")
}

/// The content hash of an IR text whose `hash` field holds `stored`.
pub fn content_hash(text: &str, stored: &str) -> String {
    sha256_hex(&text.replacen(stored, HASH_PLACEHOLDER, 1))
}

/// Rewrite the `hash` field of an IR text so that it matches the content (for tools and tests
/// that edit IR text on purpose). Texts without a well-formed hash are returned unchanged.
pub fn rehash(text: &str) -> String {
    let Some(stored) = find_hash(text) else {
        return text.to_string();
    };
    let clean = text.replacen(stored, HASH_PLACEHOLDER, 1);
    clean.replacen(HASH_PLACEHOLDER, &sha256_hex(&clean), 1)
}

fn find_hash(text: &str) -> Option<&str> {
    let start = text.find("\"sha256:")? + 1;
    let candidate = text.get(start..start + 71)?;
    well_formed(candidate).then_some(candidate)
}

fn well_formed(hash: &str) -> bool {
    hash.strip_prefix("sha256:").is_some_and(|hex| {
        hex.len() == 64
            && hex
                .bytes()
                .all(|b| b.is_ascii_digit() || (b'a'..=b'f').contains(&b))
    })
}

/// Check the stored hash against the content.
pub(crate) fn check_hash(text: &str, stored: &str) -> Result<(), Problem> {
    if !well_formed(stored) {
        return Err(Problem::MalformedHash(stored.to_string()));
    }
    let actual = content_hash(text, stored);
    if actual == stored {
        Ok(())
    } else {
        Err(Problem::HashMismatch {
            stored: stored.to_string(),
            actual,
        })
    }
}
