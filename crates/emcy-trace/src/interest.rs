//! [`Interest`]: which identifiers a caller wants decoded, so that readers
//! skip the time and data of every other frame.

use std::fmt;

use crate::FoldRule;

/// Which identifiers the caller wants decoded. Parsers read the id first and
/// skip decoding time and data for everything else.
///
/// Some wanted standard ids can be given a content filter: a frame on them
/// whose data the filter rejects is only timed ([`Scan::Timed`](crate::Scan::Timed)): the caller
/// needs its time but nothing else (a heartbeat, when only boot-ups matter).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Interest {
    standard: [u64; 32],
    /// Every extended id (tests, conversions).
    all_extended: bool,
    /// Single extended ids (a node whose 0x1014 moved its EMCY to 29 bits).
    extended: Vec<u32>,
    /// Standard ids under `content`.
    filtered: [u64; 32],
    content: ContentFilter,
    /// Standard ids whose repeated frames a reader's hot loop may fold
    /// ([`crate::fold`]).
    foldable: [u64; 32],
    /// The bits that must repeat for a fold, by id (sorted; ids not here:
    /// every bit).
    fold_masks: Vec<(u32, u64)>,
    /// Wanted standard ids whose frames do not move the input's time (a
    /// drive's PDOs before their mapping is known, [`Interest::untime`]).
    untimed: [u64; 32],
    /// Standard ids whose frames need not end a run of folds
    /// ([`Interest::keep_inside`]).
    inside: [u64; 32],
    /// Error frames are wanted (time and data decoded), whatever their
    /// class bits: candump writes those bits as an extended id with its
    /// error flag, which no list of ids could cover.
    errors: bool,
    /// CAN FD frames on wanted ids are wanted too (the analysis decodes no
    /// FD frame; counting every frame per id and timing it needs them).
    fd: bool,
    /// Every frame is timed ([`Interest::every_frame`]).
    every_frame: bool,
    /// Standard ids whose frames are only timed, one by one: a reader
    /// that can time a line without decoding it hands it over so
    /// ([`Interest::hand_over`]), the others decode it.
    handed: [u64; 32],
}

/// candump's flag for an error frame in an extended id.
const ERROR_FLAG: u32 = 0x2000_0000;

/// Whether a frame's data matters (see [`Interest`]), from its head.
#[derive(Clone, Copy)]
pub struct ContentFilter(pub fn(u32, DataHead) -> bool);

impl ContentFilter {
    fn any(_: u32, _: DataHead) -> bool {
        true
    }
}

/// What a [`ContentFilter`] decides by: a frame's data length and its
/// first three bytes. That is all the analysis asks (an SDO frame's
/// command and object index, a heartbeat's length), and all a reader need
/// parse to ask it: a busy trace's SDO traffic is mostly timed only, and
/// parsing its 8 bytes cost about 50 instructions more a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DataHead {
    len: u8,
    bytes: [u8; 3],
}

impl DataHead {
    /// The head of `data`.
    pub fn of(data: &[u8]) -> DataHead {
        let mut bytes = [0u8; 3];
        for (b, d) in bytes.iter_mut().zip(data) {
            *b = *d;
        }
        DataHead {
            len: data.len().min(usize::from(u8::MAX)) as u8,
            bytes,
        }
    }

    /// Of data `len` bytes long whose first bytes are `bytes` (those past
    /// `len` are ignored).
    pub fn new(len: u8, bytes: [u8; 3]) -> DataHead {
        let mut head = DataHead { len, bytes };
        for (i, b) in head.bytes.iter_mut().enumerate() {
            if i >= usize::from(len) {
                *b = 0;
            }
        }
        head
    }

    /// The data's length.
    // A frame's data length, not the size of a collection.
    #[allow(clippy::len_without_is_empty)]
    pub fn len(self) -> usize {
        usize::from(self.len)
    }

    /// Its first bytes, at most three.
    pub fn head(&self) -> &[u8] {
        self.bytes.get(..self.len()).unwrap_or(&self.bytes)
    }
}

impl PartialEq for ContentFilter {
    fn eq(&self, other: &Self) -> bool {
        // Same function, same filter (only ever compared in tests).
        self.0 as usize == other.0 as usize
    }
}

impl Eq for ContentFilter {}

impl fmt::Debug for ContentFilter {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("ContentFilter")
    }
}

#[inline]
fn bit(set: &[u64; 32], id: u32) -> bool {
    set.get((id >> 6) as usize)
        .is_some_and(|word| word & (1 << (id & 63)) != 0)
}

impl Interest {
    /// Decode every frame (tests, conversions).
    pub fn all() -> Interest {
        Interest {
            standard: [u64::MAX; 32],
            all_extended: true,
            extended: Vec::new(),
            filtered: [0; 32],
            content: ContentFilter(ContentFilter::any),
            foldable: [0; 32],
            fold_masks: Vec::new(),
            untimed: [0; 32],
            inside: [0; 32],
            errors: true,
            fd: true,
            every_frame: false,
            handed: [0; 32],
        }
    }

    /// Decode no frame (a caller adds the ids it wants).
    pub fn none() -> Interest {
        Interest {
            standard: [0; 32],
            all_extended: false,
            extended: Vec::new(),
            filtered: [0; 32],
            content: ContentFilter(ContentFilter::any),
            foldable: [0; 32],
            fold_masks: Vec::new(),
            untimed: [0; 32],
            inside: [0; 32],
            errors: false,
            fd: false,
            every_frame: false,
            handed: [0; 32],
        }
    }

    /// This interest with every frame timed: every frame is wanted
    /// ([`Interest::wants`]), but a reader that can time a line without
    /// decoding it (the candump hot loop) decodes only the frames this
    /// interest [`decodes`](Interest::decodes) and hands the others over
    /// with their times ([`IdCounts::timed_lines`](crate::IdCounts::timed_lines)),
    /// those the content filter only times too. Readers that cannot do so
    /// decode every frame: [`Interest::timed_only`] is then `false`. The
    /// candump hot loop still folds, and hands each folded line over too;
    /// no frame is kept inside a run of folds, so every frame's time comes
    /// to its caller in line order.
    pub fn every_frame(&self) -> Interest {
        Interest {
            inside: [0; 32],
            errors: true,
            fd: true,
            every_frame: true,
            ..self.clone()
        }
    }

    /// Whether every frame is timed ([`Interest::every_frame`]).
    #[inline]
    pub fn times_every_frame(&self) -> bool {
        self.every_frame
    }

    /// Wants the frames on standard `id` for their times alone, each one:
    /// a reader that can time a line without decoding it (the candump hot
    /// loop) hands it over with its time
    /// ([`IdCounts::timed_lines`](crate::IdCounts::timed_lines)) and goes
    /// on, the others decode the frame. They move no input time
    /// ([`Interest::untime`]): they are counted as the lines around them.
    pub fn hand_over(&mut self, id: u32) {
        self.add_standard(id);
        self.untime(id);
        if let Some(word) = self.handed.get_mut((id >> 6) as usize) {
            *word |= 1 << (id & 63);
        }
    }

    /// Whether frames on `id` are wanted for their times alone
    /// ([`Interest::hand_over`]).
    #[inline]
    pub fn hands_over(&self, id: u32, extended: bool) -> bool {
        !extended && bit(&self.handed, id)
    }

    /// Puts wanted standard ids under a content filter (one for all).
    pub fn filter_content(&mut self, ids: std::ops::RangeInclusive<u32>, content: ContentFilter) {
        self.content = content;
        for id in ids {
            if let Some(word) = self.filtered.get_mut((id >> 6) as usize) {
                *word |= 1 << (id & 63);
            }
        }
    }

    /// Changes the content filter, leaving which ids are under it as they
    /// are; whether it changed.
    pub fn set_content(&mut self, content: ContentFilter) -> bool {
        let changed = self.content != content;
        self.content = content;
        changed
    }

    /// The content filter.
    pub fn content(&self) -> ContentFilter {
        self.content
    }

    /// Takes a standard id out of the content filter: all its frames
    /// matter, one by one.
    pub fn unfilter(&mut self, id: u32) {
        for set in [&mut self.filtered, &mut self.foldable] {
            if let Some(word) = set.get_mut((id >> 6) as usize) {
                *word &= !(1 << (id & 63));
            }
        }
    }

    /// Puts a standard id back under the content filter (after
    /// [`Interest::unfilter`]); its frames stay unfoldable.
    pub fn refilter(&mut self, id: u32) {
        if let Some(word) = self.filtered.get_mut((id >> 6) as usize) {
            *word |= 1 << (id & 63);
        }
    }

    /// Lets readers fold frames on the standard ids in `ids` that repeat
    /// the one before on their id.
    pub fn fold(&mut self, ids: std::ops::RangeInclusive<u32>) {
        for id in ids {
            if let Some(word) = self.foldable.get_mut((id >> 6) as usize) {
                *word |= 1 << (id & 63);
            }
        }
    }

    /// Lets frames on the standard ids in `ids` stay inside a run of folds
    /// ([`Folds::keep_inside`](crate::Folds::keep_inside)) rather than end it: the caller takes them
    /// after the run's folds when it takes those whole, so what they do
    /// must not depend on what the folds change, nor change the interest.
    pub fn keep_inside(&mut self, ids: std::ops::RangeInclusive<u32>) {
        for id in ids {
            if let Some(word) = self.inside.get_mut((id >> 6) as usize) {
                *word |= 1 << (id & 63);
            }
        }
    }

    /// Every frame ends a run of folds again (what the frames kept inside
    /// do came to depend on the folds).
    pub fn end_runs_at_frames(&mut self) {
        self.inside = [0; 32];
    }

    /// Whether a frame on a standard id may stay inside a run of folds.
    #[inline]
    pub fn keeps_inside(&self, id: u32) -> bool {
        bit(&self.inside, id)
    }

    /// Lets readers fold frames on standard `id` whose data (the first 8
    /// bytes as a little-endian word) repeats the one before under `mask`.
    pub fn fold_masked(&mut self, id: u32, mask: u64) {
        self.fold(id..=id);
        match self.fold_masks.binary_search_by_key(&id, |&(i, _)| i) {
            Ok(i) => {
                if let Some(m) = self.fold_masks.get_mut(i) {
                    m.1 = mask;
                }
            }
            Err(i) => self.fold_masks.insert(i, (id, mask)),
        }
    }

    /// The bits that must repeat for a fold on `id`.
    pub fn fold_mask(&self, id: u32) -> u64 {
        match self.fold_masks.binary_search_by_key(&id, |&(i, _)| i) {
            Ok(i) => self.fold_masks.get(i).map_or(u64::MAX, |m| m.1),
            Err(_) => u64::MAX,
        }
    }

    /// How frames on a foldable id fold: the bits that must repeat, and
    /// whether the content filter applies to the id.
    pub fn fold_rule(&self, id: u32) -> FoldRule {
        FoldRule {
            mask: self.fold_mask(id),
            filter: self.filters(id).then_some(self.content),
        }
    }

    /// Frames on standard `id` are wanted but move no time: a reader that
    /// spares converting a run's last time because the frame ending the
    /// run moves it again must not count on one of these.
    pub fn untime(&mut self, id: u32) {
        if let Some(word) = self.untimed.get_mut((id >> 6) as usize) {
            *word |= 1 << (id & 63);
        }
    }

    /// Whether a frame on `id` moves the input's first and last time when
    /// the caller gets it.
    #[inline]
    pub fn times(&self, id: u32, extended: bool) -> bool {
        extended || !bit(&self.untimed, id)
    }

    /// Whether a reader may fold repeated frames on a standard id.
    #[inline]
    pub fn folds(&self, id: u32) -> bool {
        bit(&self.foldable, id)
    }

    /// Whether a frame on a wanted id is only to be timed: a standard id
    /// under the content filter, and data it rejects; never with every
    /// frame timed ([`Interest::every_frame`]).
    #[inline]
    pub fn timed_only(&self, id: u32, extended: bool, data: &[u8]) -> bool {
        !self.every_frame && !extended && self.timed_only_head(id, DataHead::of(data))
    }

    /// [`Interest::timed_only`] for a standard id, from the data's head,
    /// whether every frame is timed or not: for a reader that hands such a
    /// line over with its time then (the candump hot loop).
    #[inline]
    pub fn timed_only_head(&self, id: u32, head: DataHead) -> bool {
        bit(&self.filtered, id) && !(self.content.0)(id, head)
    }

    /// Whether frames on a standard id are under the content filter.
    #[inline]
    pub fn filters(&self, id: u32) -> bool {
        bit(&self.filtered, id)
    }

    /// Wants every error frame decoded.
    pub fn add_error_frames(&mut self) {
        self.errors = true;
    }

    /// Whether error frames are wanted.
    #[inline]
    pub fn wants_error_frames(&self) -> bool {
        self.errors
    }

    /// Whether CAN FD frames on wanted ids are wanted.
    #[inline]
    pub fn wants_fd(&self) -> bool {
        self.fd
    }

    /// Whether a CAN FD frame on `id` is wanted: on a wanted id when FD
    /// frames are ([`Interest::wants_fd`]), and on an id handed over,
    /// whose frames are wanted for their times whatever their kind.
    #[inline]
    pub fn wants_fd_on(&self, id: u32, extended: bool) -> bool {
        (self.fd || self.hands_over(id, extended)) && self.wants(id, extended)
    }

    /// Wants the extended id `id`.
    pub fn add_extended(&mut self, id: u32) {
        if let Err(i) = self.extended.binary_search(&id) {
            self.extended.insert(i, id);
        }
    }

    /// Wants the standard id `id` (ids past 0x7FF are ignored).
    pub fn add_standard(&mut self, id: u32) {
        if let Some(word) = self.standard.get_mut((id >> 6) as usize) {
            *word |= 1 << (id & 63);
        }
    }

    /// No longer wants the standard id `id`: its frames are only counted
    /// again, as if it had never been added.
    pub fn remove_standard(&mut self, id: u32) {
        for set in [&mut self.standard, &mut self.untimed] {
            if let Some(word) = set.get_mut((id >> 6) as usize) {
                *word &= !(1 << (id & 63));
            }
        }
    }

    /// Wants every standard id in `ids`.
    pub fn add_standard_range(&mut self, ids: std::ops::RangeInclusive<u32>) {
        for id in ids {
            self.add_standard(id);
        }
    }

    /// Whether a frame on `id` is wanted: decoded, or with every frame
    /// timed, any frame.
    #[inline]
    pub fn wants(&self, id: u32, extended: bool) -> bool {
        self.every_frame || self.decodes(id, extended)
    }

    /// Whether a frame on `id` is to be decoded: [`Interest::wants`] but
    /// for the frames only timed when every frame is.
    #[inline]
    pub fn decodes(&self, id: u32, extended: bool) -> bool {
        if extended {
            return self.all_extended
                || (self.errors && id & ERROR_FLAG != 0)
                || self.extended.binary_search(&id).is_ok();
        }
        match self.standard.get((id >> 6) as usize) {
            Some(word) => word & (1 << (id & 63)) != 0,
            None => false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interest_bitset() {
        let mut i = Interest::none();
        i.add_standard_range(0x81..=0xFF);
        assert!(i.wants(0x81, false));
        assert!(i.wants(0xFF, false));
        assert!(!i.wants(0x80, false));
        assert!(!i.wants(0x81, true));
        assert!(!i.wants(0x7FF, false));
        assert!(!i.wants(u32::MAX, false));
        i.add_standard(5000); // out of range: ignored, no panic
        assert!(Interest::all().wants(0x1234_5678, true));
        i.add_extended(0x1234_5678);
        assert!(i.wants(0x1234_5678, true));
        assert!(!i.wants(0x1234_5679, true));
        assert!(!i.wants(0x78, false));
    }

    #[test]
    fn error_frames_are_wanted_whatever_their_class_bits() {
        let mut i = Interest::none();
        assert!(!i.wants_error_frames());
        assert!(!i.wants(0x2000_0004, true));
        i.add_error_frames();
        assert!(i.wants_error_frames());
        assert!(i.wants(0x2000_0004, true));
        assert!(i.wants(0x2000_0340, true));
        // Only ids with candump's error flag: other extended ids are not.
        assert!(!i.wants(0x0000_0004, true));
        assert!(!i.wants(0x1234_5678, true));
    }

    #[test]
    fn with_every_frame_timed_every_frame_is_wanted_and_only_its_own_decoded() {
        let mut i = Interest::none();
        i.add_standard_range(0x700..=0x77F);
        i.filter_content(0x700..=0x77F, ContentFilter(|_, d| d.head() == [0]));
        i.fold(0x701..=0x77F);
        i.untime(0x181);
        i.keep_inside(0x81..=0xFF);
        assert!(!i.times_every_frame());
        let every = i.every_frame();
        assert!(every.times_every_frame());
        for (id, extended) in [(0x181, false), (0x7FF, false), (0x1234_5678, true)] {
            assert!(every.wants(id, extended), "{id:#x}");
            assert_eq!(
                every.decodes(id, extended),
                i.wants(id, extended),
                "{id:#x}"
            );
        }
        assert!(every.decodes(0x705, false));
        // Frames are folded and move the input's time as before, none is
        // kept inside a run; one the filter rejects is only timed by a
        // reader that hands it over with its time, the others decode it.
        assert_eq!(every.folds(0x705), i.folds(0x705));
        assert!(i.timed_only(0x705, false, &[1]) && !every.timed_only(0x705, false, &[1]));
        assert!(every.timed_only_head(0x705, DataHead::of(&[1])));
        assert!(!every.timed_only_head(0x705, DataHead::of(&[0])));
        assert!(!every.times(0x181, false) && every.times(0x182, false));
        assert!(!every.keeps_inside(0x85));
        assert!(every.wants_error_frames() && every.wants_fd());
    }

    #[test]
    fn a_removed_id_is_as_never_added() {
        let mut i = Interest::none();
        i.add_standard_range(0x181..=0x183);
        i.untime(0x182);
        let before = i.clone();
        i.add_standard(0x185);
        i.untime(0x185);
        i.remove_standard(0x185);
        assert_eq!(i, before);
        i.remove_standard(0x182);
        assert!(!i.wants(0x182, false));
        assert!(i.times(0x182, false));
        assert!(i.wants(0x181, false) && i.wants(0x183, false));
        i.remove_standard(5000); // out of range: ignored, no panic
    }
}
