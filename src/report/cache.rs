//! A direct-mapped cache for the texts renderers write on every event
//! (descriptions, payload fragments): the slot is chosen by the caller from
//! the key's bits; a miss recomputes and replaces. No hashing, bounded size.

use crate::canopen::profile::Profile;

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

/// A profile's identity for caches: profiles live for the whole run.
pub fn profile_key(profile: &Profile) -> usize {
    std::ptr::from_ref(profile) as usize
}

/// Key and slot of a code's description under a profile.
pub fn description_key(profile: &Profile, code: u16) -> ((usize, u16), usize) {
    let key = (profile_key(profile), code);
    let slot = usize::from(code) ^ usize::from(code >> 8) ^ (key.0 >> 4);
    (key, slot)
}

#[cfg(test)]
mod tests {
    use super::*;

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
