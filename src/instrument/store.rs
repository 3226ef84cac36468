//! The calibration record in NOR flash, kept across power loss: an A/B store of two slots
//! (docs/storage.md).
//!
//! The flash given to [`RecordStore::new`] holds two slots of `slot_bytes` each, slot 0 at offset 0 and slot 1
//! right after it; each is a whole number of erase sectors (boards use one 16-KiB sector per slot). A slot
//! holds at most one record: a [`HEADER_BYTES`]-byte header, padded with 0xFF to the flash's write (and read)
//! granule, then the payload, padded with 0xFF to the write granule.
//!
//! | offset | bytes | field |
//! |---|---|---|
//! | 0 | 4 | magic [`MAGIC`], ASCII `SCAL` |
//! | 4 | 2 | format version [`FORMAT_VERSION`], u16 little-endian |
//! | 6 | 2 | payload offset: bytes from the slot start to the payload (the padded header), u16 LE |
//! | 8 | 4 | sequence number, u32 LE: one more than the record it replaces, the first record is 1 |
//! | 12 | 4 | payload length, bytes, u32 LE |
//! | 16 | 4 | CRC-32 ([`crate::instrument::crc`]) of bytes 0..16 followed by the payload, u32 LE |
//!
//! A store writes into the slot that does not hold the newest valid record: it erases the sectors the record
//! will occupy, writes the payload, and writes the header last. A store cut at any point leaves that slot
//! without a valid header (or with a CRC that does not match), and the other slot, which it never touches,
//! keeps the previous record. A load validates both slots (magic, version, payload offset, length within the
//! slot, CRC over header fields and payload) and takes the valid one with the higher sequence number,
//! compared in serial-number arithmetic so that the step from `u32::MAX` to 0 is still "newer".
//!
//! The payload is streamed through a [`CHUNK_BYTES`] buffer on the stack in both directions: a record as
//! large as the slot is never held in RAM.

use embedded_storage::nor_flash::{NorFlash, NorFlashError, NorFlashErrorKind};

use crate::instrument::crc::Crc32;

/// The first four bytes of a record: ASCII `SCAL`. Neither all ones (erased) nor all zeros.
pub const MAGIC: [u8; 4] = *b"SCAL";

/// The record format this code writes and the only one it loads.
pub const FORMAT_VERSION: u16 = 1;

/// Header bytes before padding: magic, version, payload offset, sequence, length, CRC.
pub const HEADER_BYTES: usize = 20;

/// Bytes of the header covered by the CRC (all but the CRC itself).
const CRC_COVERED_HEADER_BYTES: usize = 16;

/// The bytes moved per flash read or write: the stack buffer of the streaming. The flash's READ_SIZE and
/// WRITE_SIZE must divide it.
pub const CHUNK_BYTES: usize = 64;

/// The sequence number of the first record in an empty store.
pub const FIRST_SEQUENCE: u32 = 1;

/// Number of slots.
pub const SLOTS: u8 = 2;

/// What went wrong in the store.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum StoreError {
    /// The flash refused an operation (the flash's error, as its generic kind).
    Flash(NorFlashErrorKind),
    /// `len` bytes asked for where at most `max` fit: a record larger than a slot holds, or a read past the
    /// end of a record.
    TooLarge {
        /// Bytes asked for.
        len: usize,
        /// The most that fit.
        max: usize,
    },
    /// The flash cannot hold this layout: the slot is not a whole number of erase sectors, the flash is smaller
    /// than two slots, the slot does not hold a header, or the flash's read or write granule does not divide
    /// [`CHUNK_BYTES`].
    Layout,
    /// The payload source (the `fill` callback of [`RecordStore::store`]) could not deliver its bytes; the
    /// previous record is intact.
    Payload,
    /// The record read back after a store is not the record written (the flash did not keep the bytes); the
    /// previous record is intact.
    Verify,
}

impl core::fmt::Display for StoreError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            StoreError::Flash(kind) => write!(f, "flash error: {kind}"),
            StoreError::TooLarge { len, max } => write!(f, "{len} bytes asked for, at most {max} fit"),
            StoreError::Layout => write!(f, "the flash cannot hold two slots of this size"),
            StoreError::Payload => write!(f, "the payload source failed"),
            StoreError::Verify => write!(f, "the record read back differs from the record written"),
        }
    }
}

impl core::error::Error for StoreError {}

/// The flash error as a [`StoreError`].
fn flash_error<E: NorFlashError>(e: E) -> StoreError {
    StoreError::Flash(e.kind())
}

/// A valid record found by [`RecordStore::newest`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RecordInfo {
    /// The slot that holds it, 0 or 1.
    pub slot: u8,
    /// Its sequence number.
    pub sequence: u32,
    /// Payload length, bytes.
    pub len: usize,
}

/// A record whose header is whole (magic, version, payload offset, a length the slot holds, a written CRC) but
/// whose CRC does not match its header and payload: a record damaged after it was stored (or a store cut while
/// its CRC was being programmed, the last bytes it writes).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DamagedRecord {
    /// The slot that holds it, 0 or 1.
    pub slot: u8,
    /// The sequence number its header gives.
    pub sequence: u32,
}

/// What [`RecordStore::scan`] found: the newest valid record, and a damaged record newer than it, if any (the
/// record a load would have taken had it not been damaged).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct StoreScan {
    /// The newest valid record.
    pub newest: Option<RecordInfo>,
    /// A damaged record newer than [`StoreScan::newest`] (or the only record with a header).
    pub damaged_newer: Option<DamagedRecord>,
}

/// What one slot holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum SlotContent {
    /// No whole header: erased, never written, or a store cut before its header was complete.
    Empty,
    /// A valid record.
    Valid(RecordInfo),
    /// A whole header whose CRC does not match.
    Damaged(DamagedRecord),
}

/// What a successful [`RecordStore::store`] did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct StoreReport {
    /// The new record's sequence number.
    pub sequence: u32,
    /// The slot it went to, 0 or 1.
    pub slot: u8,
    /// Sector erases this store did.
    pub erases: u32,
    /// Bytes programmed: the padded payload and the padded header.
    pub bytes_written: usize,
}

/// Whether sequence number `a` is newer than `b` in serial-number arithmetic: `a` is at most 2^31 - 1 steps
/// ahead of `b`, so that 0 follows `u32::MAX`. The two valid records of a store differ by one.
pub fn sequence_is_newer(a: u32, b: u32) -> bool {
    (a.wrapping_sub(b) as i32) > 0
}

/// `n` rounded up to a multiple of `granule` (a power of two or any divisor of [`CHUNK_BYTES`]; not zero).
const fn round_up(n: usize, granule: usize) -> usize {
    n.div_ceil(granule) * granule
}

/// The CRC-covered header fields of a record.
fn header_fields(payload_offset: u16, sequence: u32, len: u32) -> [u8; CRC_COVERED_HEADER_BYTES] {
    let mut h = [0u8; CRC_COVERED_HEADER_BYTES];
    h[0..4].copy_from_slice(&MAGIC);
    h[4..6].copy_from_slice(&FORMAT_VERSION.to_le_bytes());
    h[6..8].copy_from_slice(&payload_offset.to_le_bytes());
    h[8..12].copy_from_slice(&sequence.to_le_bytes());
    h[12..16].copy_from_slice(&len.to_le_bytes());
    h
}

/// A little-endian u32 at `at` of `bytes` (which holds at least `at + 4` bytes).
fn le_u32(bytes: &[u8], at: usize) -> u32 {
    let mut w = [0u8; 4];
    w.copy_from_slice(&bytes[at..at + 4]);
    u32::from_le_bytes(w)
}

/// The A/B calibration record store over a NOR flash (see the module documentation for the layout and the
/// order of a store).
///
/// Use: [`RecordStore::newest`] finds the record to load and [`RecordStore::read`] streams its payload out;
/// [`RecordStore::store`] streams a new payload in through a callback. A [`RecordInfo`] stays valid across one
/// store (which writes the other slot); after a second store or [`RecordStore::erase_all`], call
/// [`RecordStore::newest`] again.
pub struct RecordStore<F: NorFlash> {
    flash: F,
    slot_bytes: u32,
    /// Bytes from a slot's start to its payload: the header padded to the read and write granules.
    payload_offset: u32,
}

impl<F: NorFlash> RecordStore<F> {
    /// The read and write granule of the layout: the larger of READ_SIZE and WRITE_SIZE.
    const GRANULE: usize = if F::READ_SIZE > F::WRITE_SIZE { F::READ_SIZE } else { F::WRITE_SIZE };

    /// A store of two slots of `slot_bytes` each at the start of `flash`. [`StoreError::Layout`] unless
    /// `slot_bytes` is a non-zero multiple of the flash's ERASE_SIZE, the flash holds two slots, READ_SIZE and
    /// WRITE_SIZE divide [`CHUNK_BYTES`] and ERASE_SIZE, and a slot holds the header.
    pub fn new(flash: F, slot_bytes: u32) -> Result<Self, StoreError> {
        let granule = Self::GRANULE;
        let divides = |g: usize| g > 0 && CHUNK_BYTES % g == 0 && F::ERASE_SIZE % g == 0;
        let slot = slot_bytes as usize;
        let payload_offset = round_up(HEADER_BYTES, granule);
        let fits = slot > payload_offset
            && F::ERASE_SIZE > 0
            && slot % F::ERASE_SIZE == 0
            && slot_bytes.checked_mul(2).is_some_and(|two| two as usize <= flash.capacity());
        if !(divides(F::READ_SIZE) && divides(F::WRITE_SIZE) && fits) {
            return Err(StoreError::Layout);
        }
        Ok(RecordStore { flash, slot_bytes, payload_offset: payload_offset as u32 })
    }

    /// The largest payload a record can have, bytes: the slot less the padded header.
    pub fn max_payload(&self) -> usize {
        (self.slot_bytes - self.payload_offset) as usize
    }

    /// Bytes per slot.
    pub fn slot_bytes(&self) -> u32 {
        self.slot_bytes
    }

    /// The flash offset of slot `slot`'s start.
    fn slot_base(&self, slot: u8) -> u32 {
        u32::from(slot) * self.slot_bytes
    }

    /// The newest valid record, `None` if neither slot holds one. Reads both slots whole (their payloads
    /// through the CRC).
    pub fn newest(&mut self) -> Result<Option<RecordInfo>, StoreError> {
        Ok(self.scan()?.newest)
    }

    /// The newest valid record and a damaged record newer than it, if any: a load that falls back to an older
    /// record because the newer one is damaged says so. Reads both slots whole.
    pub fn scan(&mut self) -> Result<StoreScan, StoreError> {
        let contents = [self.slot_content(0)?, self.slot_content(1)?];
        let mut scan = StoreScan::default();
        for content in contents {
            if let SlotContent::Valid(info) = content {
                if scan.newest.is_none_or(|n| sequence_is_newer(info.sequence, n.sequence)) {
                    scan.newest = Some(info);
                }
            }
        }
        for content in contents {
            if let SlotContent::Damaged(d) = content {
                if scan.newest.is_none_or(|n| sequence_is_newer(d.sequence, n.sequence)) {
                    scan.damaged_newer = Some(d);
                }
            }
        }
        Ok(scan)
    }

    /// The record in `slot` if it is valid: magic, version, payload offset, length within the slot, CRC.
    fn validate_slot(&mut self, slot: u8) -> Result<Option<RecordInfo>, StoreError> {
        Ok(match self.slot_content(slot)? {
            SlotContent::Valid(info) => Some(info),
            _ => None,
        })
    }

    /// What `slot` holds: a valid record, a whole header with a CRC that does not match, or no whole header.
    fn slot_content(&mut self, slot: u8) -> Result<SlotContent, StoreError> {
        let base = self.slot_base(slot);
        let mut head = [0u8; CHUNK_BYTES];
        let head = &mut head[..self.payload_offset as usize];
        self.flash.read(base, head).map_err(flash_error)?;
        let payload_offset = u16::from_le_bytes([head[6], head[7]]);
        let len = le_u32(head, 12) as usize;
        if head[0..4] != MAGIC
            || u16::from_le_bytes([head[4], head[5]]) != FORMAT_VERSION
            || u32::from(payload_offset) != self.payload_offset
            || len > self.max_payload()
        {
            return Ok(SlotContent::Empty);
        }
        let mut crc = Crc32::new();
        crc.update(&head[..CRC_COVERED_HEADER_BYTES]);
        let stored_crc = le_u32(head, CRC_COVERED_HEADER_BYTES);
        let mut buf = [0u8; CHUNK_BYTES];
        let mut offset = 0;
        while offset < len {
            let n = (len - offset).min(CHUNK_BYTES);
            let chunk = &mut buf[..round_up(n, F::READ_SIZE)];
            self.flash.read(base + self.payload_offset + offset as u32, chunk).map_err(flash_error)?;
            crc.update(&chunk[..n]);
            offset += n;
        }
        let sequence = le_u32(head, 8);
        Ok(if crc.finish() == stored_crc {
            SlotContent::Valid(RecordInfo { slot, sequence, len })
        } else if stored_crc == u32::MAX {
            // The CRC's bytes still erased: a store cut before its last bytes, not a damaged record.
            SlotContent::Empty
        } else {
            SlotContent::Damaged(DamagedRecord { slot, sequence })
        })
    }

    /// Reads `out.len()` payload bytes of the record `info` from payload offset `offset`.
    /// [`StoreError::TooLarge`] if that runs past the record's end, [`StoreError::Layout`] if `info` names no
    /// slot or a length no slot holds. `info` must come from [`RecordStore::newest`]
    /// with at most one store since (see [`RecordStore`]); the bytes are not checked again.
    pub fn read(&mut self, info: &RecordInfo, offset: usize, out: &mut [u8]) -> Result<(), StoreError> {
        if info.slot >= SLOTS || info.len > self.max_payload() {
            return Err(StoreError::Layout);
        }
        let end = offset.saturating_add(out.len());
        if end > info.len {
            return Err(StoreError::TooLarge { len: end, max: info.len });
        }
        let start = self.slot_base(info.slot) + self.payload_offset + offset as u32;
        if F::READ_SIZE == 1 {
            return self.flash.read(start, out).map_err(flash_error);
        }
        // Through an aligned bounce buffer; the padding after the payload keeps the rounded reads in the slot.
        let granule = F::READ_SIZE as u32;
        let mut buf = [0u8; CHUNK_BYTES];
        let mut done = 0;
        while done < out.len() {
            let at = start + done as u32;
            let aligned = at - at % granule;
            let skip = (at - aligned) as usize;
            let n = (out.len() - done).min(CHUNK_BYTES - skip);
            let chunk = &mut buf[..round_up(skip + n, F::READ_SIZE)];
            self.flash.read(aligned, chunk).map_err(flash_error)?;
            out[done..done + n].copy_from_slice(&chunk[skip..skip + n]);
            done += n;
        }
        Ok(())
    }

    /// Stores a new record of `len` payload bytes. `fill(offset, chunk)` writes payload bytes
    /// `offset..offset + chunk.len()` into `chunk`; it is called in order of increasing offset with chunks of at
    /// most [`CHUNK_BYTES`] that cover `0..len` once. A `fill` error (use [`StoreError::Payload`]) ends the store.
    ///
    /// The record goes into the slot that does not hold the newest valid record: its sectors are erased, the
    /// payload is written, the header last, and the whole record is then read back and validated. On any error
    /// the previous record is intact and stays the newest. [`StoreError::TooLarge`] (before touching the flash)
    /// if `len` exceeds [`RecordStore::max_payload`].
    pub fn store(
        &mut self,
        len: usize,
        mut fill: impl FnMut(usize, &mut [u8]) -> Result<(), StoreError>,
    ) -> Result<StoreReport, StoreError> {
        let max = self.max_payload();
        if len > max {
            return Err(StoreError::TooLarge { len, max });
        }
        let (slot, sequence) = match self.newest()? {
            None => (0, FIRST_SEQUENCE),
            Some(n) => (1 - n.slot, n.sequence.wrapping_add(1)),
        };
        let base = self.slot_base(slot);
        let record_end = self.payload_offset as usize + round_up(len, F::WRITE_SIZE);
        let sectors = record_end.div_ceil(F::ERASE_SIZE) as u32;
        for s in 0..sectors {
            let from = base + s * F::ERASE_SIZE as u32;
            self.flash.erase(from, from + F::ERASE_SIZE as u32).map_err(flash_error)?;
        }
        // The payload (the length fits a u32: it is below the slot size).
        let fields = header_fields(self.payload_offset as u16, sequence, len as u32);
        let mut crc = Crc32::new();
        crc.update(&fields);
        let mut buf = [0xFFu8; CHUNK_BYTES];
        let mut offset = 0;
        let mut bytes_written = 0;
        while offset < len {
            let n = (len - offset).min(CHUNK_BYTES);
            fill(offset, &mut buf[..n])?;
            crc.update(&buf[..n]);
            let padded = round_up(n, F::WRITE_SIZE);
            buf[n..padded].fill(0xFF);
            self.flash.write(base + self.payload_offset + offset as u32, &buf[..padded]).map_err(flash_error)?;
            bytes_written += padded;
            offset += n;
        }
        // The header last: until its last byte is programmed the slot holds no valid record.
        let mut head = [0xFFu8; CHUNK_BYTES];
        head[..CRC_COVERED_HEADER_BYTES].copy_from_slice(&fields);
        head[CRC_COVERED_HEADER_BYTES..HEADER_BYTES].copy_from_slice(&crc.finish().to_le_bytes());
        let head = &head[..self.payload_offset as usize];
        self.flash.write(base, head).map_err(flash_error)?;
        bytes_written += head.len();
        match self.validate_slot(slot)? {
            Some(info) if info.sequence == sequence && info.len == len => {}
            _ => return Err(StoreError::Verify),
        }
        Ok(StoreReport { sequence, slot, erases: sectors, bytes_written })
    }

    /// [`RecordStore::store`] of a payload held in memory.
    pub fn store_bytes(&mut self, payload: &[u8]) -> Result<StoreReport, StoreError> {
        self.store(payload.len(), |offset, chunk| {
            let src = payload.get(offset..offset + chunk.len()).ok_or(StoreError::Payload)?;
            chunk.copy_from_slice(src);
            Ok(())
        })
    }

    /// Erases both slots (every record is gone; the next store has sequence [`FIRST_SEQUENCE`]). Returns the
    /// number of sector erases.
    pub fn erase_all(&mut self) -> Result<u32, StoreError> {
        let sectors = 2 * self.slot_bytes / F::ERASE_SIZE as u32;
        for s in 0..sectors {
            let from = s * F::ERASE_SIZE as u32;
            self.flash.erase(from, from + F::ERASE_SIZE as u32).map_err(flash_error)?;
        }
        Ok(sectors)
    }

    /// Gives the flash back.
    pub fn release(self) -> F {
        self.flash
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use embedded_storage::nor_flash::{check_erase, check_read, check_write, ErrorType, ReadNorFlash};

    /// A RAM NOR flash with AND-on-write, checked alignment and bounds.
    struct RamFlash<const READ: usize, const WRITE: usize, const ERASE: usize> {
        bytes: Vec<u8>,
    }

    impl<const READ: usize, const WRITE: usize, const ERASE: usize> RamFlash<READ, WRITE, ERASE> {
        fn erased(sectors: usize) -> Self {
            RamFlash { bytes: vec![0xFF; sectors * ERASE] }
        }
    }

    impl<const READ: usize, const WRITE: usize, const ERASE: usize> ErrorType for RamFlash<READ, WRITE, ERASE> {
        type Error = NorFlashErrorKind;
    }

    impl<const READ: usize, const WRITE: usize, const ERASE: usize> ReadNorFlash for RamFlash<READ, WRITE, ERASE> {
        const READ_SIZE: usize = READ;
        fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
            check_read(self, offset, bytes.len())?;
            bytes.copy_from_slice(&self.bytes[offset as usize..offset as usize + bytes.len()]);
            Ok(())
        }
        fn capacity(&self) -> usize {
            self.bytes.len()
        }
    }

    impl<const READ: usize, const WRITE: usize, const ERASE: usize> NorFlash for RamFlash<READ, WRITE, ERASE> {
        const WRITE_SIZE: usize = WRITE;
        const ERASE_SIZE: usize = ERASE;
        fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
            check_erase(self, from, to)?;
            self.bytes[from as usize..to as usize].fill(0xFF);
            Ok(())
        }
        fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
            check_write(self, offset, bytes.len())?;
            for (d, s) in self.bytes[offset as usize..].iter_mut().zip(bytes) {
                *d &= *s;
            }
            Ok(())
        }
    }

    type Flash = RamFlash<1, 4, 1024>;

    fn payload(len: usize, seed: u8) -> Vec<u8> {
        (0..len).map(|i| (i as u8).wrapping_mul(31).wrapping_add(seed)).collect()
    }

    fn load<F: NorFlash>(store: &mut RecordStore<F>) -> Option<(RecordInfo, Vec<u8>)> {
        let info = store.newest().unwrap()?;
        let mut out = vec![0u8; info.len];
        store.read(&info, 0, &mut out).unwrap();
        Some((info, out))
    }

    /// Writes a record with any sequence number and version straight into `slot`, as a store would.
    fn write_raw(flash: &mut Flash, slot: u32, version: u16, sequence: u32, payload: &[u8]) {
        let base = slot * 1024;
        flash.erase(base, base + 1024).unwrap();
        let mut fields = header_fields(20, sequence, payload.len() as u32);
        fields[4..6].copy_from_slice(&version.to_le_bytes());
        let mut crc = Crc32::new();
        crc.update(&fields);
        crc.update(payload);
        let mut padded = payload.to_vec();
        padded.resize(round_up(payload.len(), 4), 0xFF);
        flash.write(base + 20, &padded).unwrap();
        let mut head = fields.to_vec();
        head.extend_from_slice(&crc.finish().to_le_bytes());
        flash.write(base, &head).unwrap();
    }

    #[test]
    fn newest_of_two_and_the_slots_alternate() {
        let mut store = RecordStore::new(Flash::erased(2), 1024).unwrap();
        assert_eq!(store.max_payload(), 1024 - 20);
        assert_eq!(store.newest().unwrap(), None);
        let first = store.store_bytes(&payload(300, 1)).unwrap();
        assert_eq!((first.slot, first.sequence, first.erases, first.bytes_written), (0, 1, 1, 320));
        let second = store.store_bytes(&payload(1004, 2)).unwrap();
        assert_eq!((second.slot, second.sequence), (1, 2));
        let (info, bytes) = load(&mut store).unwrap();
        assert_eq!(info, RecordInfo { slot: 1, sequence: 2, len: 1004 });
        assert_eq!(bytes, payload(1004, 2));
        let third = store.store_bytes(&payload(7, 3)).unwrap();
        assert_eq!((third.slot, third.sequence), (0, 3));
        // A new store over the same flash ("reboot") finds the same record.
        let mut again = RecordStore::new(store.release(), 1024).unwrap();
        assert_eq!(load(&mut again).unwrap(), (RecordInfo { slot: 0, sequence: 3, len: 7 }, payload(7, 3)));
    }

    #[test]
    fn a_slot_with_a_bad_crc_is_ignored() {
        let mut flash = Flash::erased(2);
        write_raw(&mut flash, 0, FORMAT_VERSION, 8, &payload(100, 4));
        write_raw(&mut flash, 1, FORMAT_VERSION, 9, &payload(100, 5));
        // One bit of the newer record's payload cleared (what NOR can do without an erase).
        flash.bytes[1024 + 20 + 57] &= !0x08;
        let mut store = RecordStore::new(flash, 1024).unwrap();
        assert_eq!(load(&mut store).unwrap(), (RecordInfo { slot: 0, sequence: 8, len: 100 }, payload(100, 4)));
        // The fall back is said: the damaged record is newer than the one loaded.
        let scan = store.scan().unwrap();
        assert_eq!(scan.damaged_newer, Some(DamagedRecord { slot: 1, sequence: 9 }));
        assert_eq!(scan.newest.map(|n| n.sequence), Some(8));
        // The next store replaces the bad slot, not the good one.
        let r = store.store_bytes(&payload(10, 6)).unwrap();
        assert_eq!((r.slot, r.sequence), (1, 9));
        // A damaged header (the length) is refused too.
        let mut flash = store.release();
        flash.bytes[1024 + 12] &= 0xF0;
        let mut store = RecordStore::new(flash, 1024).unwrap();
        assert_eq!(store.newest().unwrap().map(|i| i.sequence), Some(8));
    }

    #[test]
    fn only_a_damaged_record_newer_than_the_loaded_one_is_reported() {
        // Damaged, but older than the valid record: nothing was lost, nothing to report.
        let mut flash = Flash::erased(2);
        write_raw(&mut flash, 0, FORMAT_VERSION, 8, &payload(100, 4));
        write_raw(&mut flash, 1, FORMAT_VERSION, 9, &payload(100, 5));
        flash.bytes[20 + 3] &= !0x01;
        let mut store = RecordStore::new(flash, 1024).unwrap();
        assert_eq!(store.scan().unwrap().damaged_newer, None);
        assert_eq!(store.newest().unwrap().map(|i| i.sequence), Some(9));
        // The only record, damaged: reported, and nothing loads.
        let mut flash = Flash::erased(2);
        write_raw(&mut flash, 1, FORMAT_VERSION, 1, &payload(40, 4));
        flash.bytes[1024 + 20] &= !0x04;
        let mut store = RecordStore::new(flash, 1024).unwrap();
        let scan = store.scan().unwrap();
        assert_eq!((scan.newest, scan.damaged_newer), (None, Some(DamagedRecord { slot: 1, sequence: 1 })));
        // A header whose CRC bytes are still erased is a store cut before its last bytes: not damage.
        let mut flash = Flash::erased(2);
        write_raw(&mut flash, 0, FORMAT_VERSION, 8, &payload(100, 4));
        let fields = header_fields(20, 9, 100);
        flash.write(1024, &fields).unwrap();
        let mut store = RecordStore::new(flash, 1024).unwrap();
        let scan = store.scan().unwrap();
        assert_eq!((scan.newest.map(|n| n.sequence), scan.damaged_newer), (Some(8), None));
    }

    #[test]
    fn a_record_of_another_version_is_ignored() {
        let mut flash = Flash::erased(2);
        write_raw(&mut flash, 0, FORMAT_VERSION, 3, &payload(50, 7));
        // Newer and with a correct CRC, but of a format this code does not read.
        write_raw(&mut flash, 1, FORMAT_VERSION + 1, 4, &payload(50, 8));
        let mut store = RecordStore::new(flash, 1024).unwrap();
        assert_eq!(store.newest().unwrap(), Some(RecordInfo { slot: 0, sequence: 3, len: 50 }));
        let mut flash = store.release();
        write_raw(&mut flash, 0, FORMAT_VERSION.wrapping_sub(1), 3, &payload(50, 7));
        let mut store = RecordStore::new(flash, 1024).unwrap();
        assert_eq!(store.newest().unwrap(), None);
    }

    #[test]
    fn sequence_numbers_wrap() {
        assert!(sequence_is_newer(0, u32::MAX));
        assert!(!sequence_is_newer(u32::MAX, 0));
        assert!(sequence_is_newer(2, 1) && !sequence_is_newer(1, 2) && !sequence_is_newer(5, 5));
        let mut flash = Flash::erased(2);
        write_raw(&mut flash, 1, FORMAT_VERSION, u32::MAX, &payload(20, 1));
        write_raw(&mut flash, 0, FORMAT_VERSION, 0, &payload(20, 2));
        let mut store = RecordStore::new(flash, 1024).unwrap();
        assert_eq!(store.newest().unwrap(), Some(RecordInfo { slot: 0, sequence: 0, len: 20 }));
        let r = store.store_bytes(&payload(20, 3)).unwrap();
        assert_eq!((r.slot, r.sequence), (1, 1));
    }

    #[test]
    fn granules_larger_than_a_byte_and_unaligned_reads() {
        // READ_SIZE 4 and WRITE_SIZE 8: the header pads to 24 bytes, reads at any offset go through the bounce
        // buffer.
        let mut store = RecordStore::new(RamFlash::<4, 8, 512>::erased(4), 1024).unwrap();
        assert_eq!(store.max_payload(), 1000);
        let data = payload(997, 9);
        let r = store.store_bytes(&data).unwrap();
        assert_eq!((r.erases, r.bytes_written), (2, 24 + 1000));
        let info = store.newest().unwrap().unwrap();
        for (offset, len) in [(0, 997), (1, 5), (3, 130), (63, 66), (990, 7), (996, 1), (997, 0)] {
            let mut out = vec![0u8; len];
            store.read(&info, offset, &mut out).unwrap();
            assert_eq!(out, data[offset..offset + len], "offset {offset} len {len}");
        }
        let mut out = [0u8; 2];
        assert_eq!(store.read(&info, 996, &mut out), Err(StoreError::TooLarge { len: 998, max: 997 }));
        // A small record erases one sector of the two in its slot.
        assert_eq!(store.store_bytes(&data[..100]).unwrap().erases, 1);
    }

    #[test]
    fn layouts_the_store_refuses() {
        assert_eq!(RecordStore::new(Flash::erased(2), 1000).err(), Some(StoreError::Layout));
        assert_eq!(RecordStore::new(Flash::erased(3), 2048).err(), Some(StoreError::Layout));
        assert_eq!(RecordStore::new(Flash::erased(2), 0).err(), Some(StoreError::Layout));
        assert_eq!(RecordStore::new(RamFlash::<1, 128, 1024>::erased(2), 1024).err(), Some(StoreError::Layout));
        assert_eq!(RecordStore::new(RamFlash::<1, 1, 16>::erased(2), 16).err(), Some(StoreError::Layout));
        assert!(RecordStore::new(Flash::erased(4), 2048).is_ok());
    }

    #[test]
    fn a_failed_fill_or_a_record_too_large_keeps_the_old_record() {
        let mut store = RecordStore::new(Flash::erased(2), 1024).unwrap();
        store.store_bytes(&payload(600, 1)).unwrap();
        let too_large = store.store(1005, |_, _| Ok(()));
        assert_eq!(too_large, Err(StoreError::TooLarge { len: 1005, max: 1004 }));
        let failed = store.store(900, |offset, chunk| {
            chunk.fill(0x5A);
            if offset >= 512 {
                Err(StoreError::Payload)
            } else {
                Ok(())
            }
        });
        assert_eq!(failed, Err(StoreError::Payload));
        assert_eq!(load(&mut store).unwrap(), (RecordInfo { slot: 0, sequence: 1, len: 600 }, payload(600, 1)));
        assert_eq!(store.erase_all().unwrap(), 2);
        assert_eq!(store.newest().unwrap(), None);
    }

    #[test]
    fn display_says_what_failed() {
        let text = format!("{}", StoreError::TooLarge { len: 20000, max: 16364 });
        assert_eq!(text, "20000 bytes asked for, at most 16364 fit");
        assert!(format!("{}", StoreError::Flash(NorFlashErrorKind::NotAligned)).contains("aligned"));
    }
}
