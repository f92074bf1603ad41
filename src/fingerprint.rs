//! Stable content fingerprints: what the build's stage graph keys its
//! stages by and what the state folder records. A fingerprint is the 128-bit
//! XXH3 of a byte stream with a fixed (zero) seed, so it is the same in every
//! run, process and machine (std's `DefaultHasher` is randomly keyed per
//! process and documented as unstable across releases). Not a defence against
//! crafted collisions: the inputs are the user's own files, and a collision
//! would only reuse a stale picture.
//!
//! Every value is fed with its length or a fixed width, so `("ab", "c")` and
//! `("a", "bc")` differ; each fingerprint starts with a domain tag, so an
//! input fingerprint never equals a settings fingerprint by construction.

use std::fmt;

use xxhash_rust::xxh3::Xxh3;

/// A 128-bit content fingerprint.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Fingerprint(u128);

impl Fingerprint {
    /// The fingerprint of `bytes` alone (a file's content).
    pub fn of_bytes(bytes: &[u8]) -> Self {
        Fingerprint(xxhash_rust::xxh3::xxh3_128(bytes))
    }

    /// Reads the 32 hex digits [`Fingerprint`]'s `Display` writes.
    pub fn parse(text: &str) -> Option<Self> {
        if text.len() != 32 {
            return None;
        }
        u128::from_str_radix(text, 16).ok().map(Fingerprint)
    }

    /// The fingerprint as 16 bytes (little-endian), for binary files.
    pub fn to_bytes(self) -> [u8; 16] {
        self.0.to_le_bytes()
    }

    /// The inverse of [`Fingerprint::to_bytes`].
    pub fn from_bytes(bytes: [u8; 16]) -> Self {
        Fingerprint(u128::from_le_bytes(bytes))
    }
}

impl fmt::Display for Fingerprint {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:032x}", self.0)
    }
}

// In the manifest a fingerprint is its hex text.
impl serde::Serialize for Fingerprint {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.collect_str(self)
    }
}

impl<'de> serde::Deserialize<'de> for Fingerprint {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let text = String::deserialize(deserializer)?;
        Fingerprint::parse(&text)
            .ok_or_else(|| serde::de::Error::custom("expected 32 hex digits"))
    }
}

/// Builds a fingerprint from typed parts.
pub struct Fingerprinter(Xxh3);

impl Fingerprinter {
    /// A new fingerprint of the kind `domain` (`"inputs"`, `"settings"`, ...).
    pub fn new(domain: &str) -> Self {
        let mut f = Fingerprinter(Xxh3::new());
        f.str(domain);
        f
    }

    /// Adds a byte string (with its length).
    pub fn bytes(&mut self, bytes: &[u8]) -> &mut Self {
        self.u64(bytes.len() as u64);
        self.0.update(bytes);
        self
    }

    /// Adds a string (with its length).
    pub fn str(&mut self, text: &str) -> &mut Self {
        self.bytes(text.as_bytes())
    }

    /// Adds an integer.
    pub fn u64(&mut self, value: u64) -> &mut Self {
        self.0.update(&value.to_le_bytes());
        self
    }

    /// Adds a float by its bits (so `-0.0` and `0.0` differ, as their
    /// layouts may).
    pub fn f64(&mut self, value: f64) -> &mut Self {
        self.u64(value.to_bits())
    }

    /// Adds another fingerprint.
    pub fn fingerprint(&mut self, value: Fingerprint) -> &mut Self {
        self.0.update(&value.to_bytes());
        self
    }

    /// Adds a typed value by its serde serialisation (compact JSON: floats
    /// in their shortest round-trip form, enums by variant name). For
    /// settings structs: every field, including one added later, is part of
    /// the fingerprint by construction, and a renamed Rust type or a
    /// reordered `Debug` impl does not change it. JSON is self-delimiting,
    /// so consecutive values cannot run into each other.
    pub fn value(&mut self, value: &impl serde::Serialize) -> &mut Self {
        /// Feeds the serialiser's output straight into the hash.
        struct Feed<'a>(&'a mut Xxh3);
        impl std::io::Write for Feed<'_> {
            fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
                self.0.update(buf);
                Ok(buf.len())
            }
            fn flush(&mut self) -> std::io::Result<()> {
                Ok(())
            }
        }
        if let Err(e) = serde_json::to_writer(Feed(&mut self.0), value) {
            // Only a map keyed by a non-string type fails, which no keyed
            // type has (a unit test serialises each); mark the value apart
            // rather than fail a build.
            debug_assert!(false, "a keyed value cannot be serialised: {e}");
            self.str("unserialisable");
        }
        self
    }

    /// The fingerprint of everything added.
    pub fn finish(&self) -> Fingerprint {
        Fingerprint(self.0.digest128())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The same content gives the same fingerprint in every process: a known
    /// value, so a change of hash function or of the feeding rules (which
    /// would turn every stored state stale) is a deliberate one.
    #[test]
    fn fingerprints_are_stable_and_typed() {
        assert_eq!(
            Fingerprint::of_bytes(b"").to_string(),
            "99aa06d3014798d86001c324468d497f"
        );
        let ab_c = Fingerprinter::new("t").str("ab").str("c").finish();
        let a_bc = Fingerprinter::new("t").str("a").str("bc").finish();
        assert_ne!(ab_c, a_bc);
        assert_ne!(
            Fingerprinter::new("t").str("x").finish(),
            Fingerprinter::new("u").str("x").finish()
        );
        let f = Fingerprinter::new("t").f64(0.5).finish();
        assert_eq!(Fingerprint::parse(&f.to_string()), Some(f));
        assert_eq!(Fingerprint::from_bytes(f.to_bytes()), f);
        assert_eq!(Fingerprint::parse("xyz"), None);
    }
}
