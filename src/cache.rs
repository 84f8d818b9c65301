//! Direct-mapped caches for what an EMCY-heavy trace looks up on every
//! event (code tables, descriptions, payload fragments): the slot comes
//! from the key's bits ([`slot`]); a miss recomputes and replaces. Bounded
//! size, no hash map.

pub struct Cache<K, V, const N: usize> {
    slots: Vec<Option<(K, V)>>,
}

impl<K, V, const N: usize> Default for Cache<K, V, N> {
    fn default() -> Self {
        Cache {
            slots: (0..N).map(|_| None).collect(),
        }
    }
}

impl<K: PartialEq + Copy, V, const N: usize> Cache<K, V, N> {
    /// The value for `key`, made by `make` unless slot `slot` holds it.
    pub fn get(&mut self, key: K, slot: usize, make: impl FnOnce() -> V) -> Option<&V> {
        let entry = self.slots.get_mut(slot % N)?;
        if !matches!(entry, Some((k, _)) if *k == key) {
            *entry = Some((key, make()));
        }
        entry.as_ref().map(|(_, v)| v)
    }
}

/// A profile's identity for caches, by address: profiles live for the whole
/// run. Generic, so this module depends on nothing.
pub fn profile_key<P>(profile: &P) -> usize {
    std::ptr::from_ref(profile) as usize
}

/// A slot for a key from all of its bits (Fibonacci hashing: the multiply
/// carries every bit into the ones kept). Keys that differ in a few bits,
/// like error codes 0x2310/0x3210/0x4310, must not share a slot: a formula
/// that dropped the high byte made them evict each other on every event.
pub fn slot(bits: u64) -> usize {
    (bits.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 40) as usize
}

/// Key and slot of a code under a profile (its description, its table entry).
pub fn profile_code_key<P>(profile: &P, code: u16) -> ((usize, u16), usize) {
    let key = (profile_key(profile), code);
    (key, slot(u64::from(code) ^ ((key.0 as u64) << 16)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn similar_keys_spread_over_the_slots() {
        // Four common codes, each with 16 manufacturer byte values.
        let mut used = std::collections::HashSet::new();
        for code in [0x2310u64, 0x3210, 0x4310, 0x8611] {
            for m in 0..16u64 {
                used.insert(slot(code | (m << 24)) % 256);
            }
        }
        assert!(
            used.len() >= 48,
            "{} of 64 keys got their own slot",
            used.len()
        );
    }

    #[test]
    fn a_hit_is_not_remade_and_a_collision_replaces() {
        let mut c: Cache<u32, String, 4> = Cache::default();
        assert_eq!(
            c.get(1, 1, || "one".into()).map(String::as_str),
            Some("one")
        );
        assert_eq!(
            c.get(1, 1, || unreachable!()).map(String::as_str),
            Some("one")
        );
        assert_eq!(
            c.get(5, 1, || "five".into()).map(String::as_str),
            Some("five")
        );
        assert_eq!(
            c.get(1, 1, || "again".into()).map(String::as_str),
            Some("again")
        );
        assert_eq!(
            c.get(2, 6, || "two".into()).map(String::as_str),
            Some("two"),
            "slot modulo size"
        );
    }
}
