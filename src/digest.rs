//! Change detection: a digest of everything an output depends on, to tell
//! whether it must be made again (database entries, a bake's interiors).
//! FNV-1a: a change detector, not a security measure, so no crate is
//! needed for it.

/// A running FNV-1a digest.
#[derive(Clone, Copy, Debug)]
pub struct Digest(u64);

impl Default for Digest {
    fn default() -> Digest {
        Digest(0xcbf2_9ce4_8422_2325)
    }
}

impl Digest {
    /// `bytes` added to the digest.
    pub fn feed(&mut self, bytes: &[u8]) {
        self.0 = bytes.iter().fold(self.0, |h, &b| {
            (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3)
        });
    }

    /// Sixteen hex digits.
    pub fn hex(&self) -> String {
        format!("{:016x}", self.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fnv1a_of_known_strings() {
        // The FNV reference values for "" and "a".
        assert_eq!(Digest::default().hex(), "cbf29ce484222325");
        let mut d = Digest::default();
        d.feed(b"a");
        assert_eq!(d.hex(), "af63dc4c8601ec8c");
    }
}
