//! The calibration record store (src/instrument/store.rs, docs/storage.md) under power cuts, on this file's own
//! RAM NOR flash: a write can only clear bits (it ANDs), a byte programmed twice without an erase is counted as
//! a fault of the store, and the power fails after exactly N byte operations (each byte programmed or erased is
//! one). The operation in progress at the cut is torn, harshly: a byte being programmed gets a random subset of
//! the bits it was clearing; a sector being erased is erased byte by byte, ascending or descending, with the
//! byte in progress half-erased (random bits set), or its whole contents become random garbage (the trait
//! says "undefined"). The erase model of a cut rotates with N (N mod 3).
//!
//! For a store over no record, over one and over two, the power is cut after N operations, the flash is
//! "rebooted" (a new `RecordStore` on the same contents) and the record loaded must be the old one or the
//! new one, bit for bit, never a corrupt one, and never none when one existed; then a further store must
//! succeed and load. On the small geometries (512-byte sectors, write granules 1 and 4) every N from 0 to the
//! store's last operation is cut. On the boards' geometry (16-KiB sectors, a 10,240-byte record, 26,644
//! operations per store) every N of the header write, the first and last 64 operations of every erase and of
//! the payload, and every 23rd N elsewhere are cut (a prime stride, so every residue of the write granule and
//! of the erase model is hit), which keeps the test at a few seconds in the dev profile.
//!
//! `cargo test -p sinscal-host --test power_cut -- --nocapture` prints the power-cut tables, the erase counts
//! and the wear.

use embedded_storage::nor_flash::{ErrorType, NorFlash, NorFlashErrorKind, ReadNorFlash};
use sinscal::instrument::store::{RecordInfo, RecordStore, StoreError, FIRST_SEQUENCE};

/// How a cut leaves the sector being erased.
#[derive(Clone, Copy, Debug)]
enum EraseCut {
    /// Erased from its first byte up; the byte in progress half-erased.
    Ascending,
    /// Erased from its last byte down; the byte in progress half-erased.
    Descending,
    /// Every byte random.
    Garbage,
}

/// One flash operation of a store, for the table.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Op {
    Erase { sector: usize },
    Write { offset: usize },
}

/// SplitMix64: the random bits of torn bytes and the payloads.
fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A RAM NOR flash that loses power after a given number of byte operations.
#[derive(Clone)]
struct CutFlash<const WRITE: usize, const ERASE: usize> {
    bytes: Vec<u8>,
    /// Programmed since the sector's last erase.
    programmed: Vec<bool>,
    /// Byte operations left before the power fails; `None`: no cut.
    budget: Option<usize>,
    powered: bool,
    erase_cut: EraseCut,
    seed: u64,
    /// Byte operations done (programmed + erased).
    ops: usize,
    sector_erases: Vec<u32>,
    bytes_programmed: usize,
    /// Bytes programmed a second time without an erase: the store must never do it.
    double_writes: usize,
    /// (first byte operation, operation) of every call.
    log: Vec<(usize, Op)>,
}

impl<const WRITE: usize, const ERASE: usize> CutFlash<WRITE, ERASE> {
    fn erased(sectors: usize) -> Self {
        CutFlash {
            bytes: vec![0xFF; sectors * ERASE],
            programmed: vec![false; sectors * ERASE],
            budget: None,
            powered: true,
            erase_cut: EraseCut::Ascending,
            seed: 0,
            ops: 0,
            sector_erases: vec![0; sectors],
            bytes_programmed: 0,
            double_writes: 0,
            log: Vec::new(),
        }
    }

    /// Plans a cut after `ops` more byte operations.
    fn cut_after(&mut self, ops: usize, erase_cut: EraseCut, seed: u64) {
        self.budget = Some(ops);
        self.erase_cut = erase_cut;
        self.seed = seed;
    }

    /// Power back on, no cut planned, counters kept.
    fn power_on(&mut self) {
        self.powered = true;
        self.budget = None;
    }

    fn random_byte(&self, address: usize) -> u8 {
        mix(self.seed ^ ((address as u64) << 20)) as u8
    }

    /// Takes one byte operation from the budget; `false` when the power fails now.
    fn take_op(&mut self) -> bool {
        match &mut self.budget {
            Some(0) => {
                self.powered = false;
                false
            }
            Some(n) => {
                *n -= 1;
                self.ops += 1;
                true
            }
            None => {
                self.ops += 1;
                true
            }
        }
    }

    fn tear_erase(&mut self, sector: usize, address: usize) {
        match self.erase_cut {
            EraseCut::Ascending | EraseCut::Descending => self.bytes[address] |= self.random_byte(address),
            EraseCut::Garbage => {
                for a in sector * ERASE..(sector + 1) * ERASE {
                    self.bytes[a] = self.random_byte(a);
                }
            }
        }
    }
}

const POWER_LOST: NorFlashErrorKind = NorFlashErrorKind::Other;

impl<const WRITE: usize, const ERASE: usize> ErrorType for CutFlash<WRITE, ERASE> {
    type Error = NorFlashErrorKind;
}

impl<const WRITE: usize, const ERASE: usize> ReadNorFlash for CutFlash<WRITE, ERASE> {
    const READ_SIZE: usize = 1;

    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
        embedded_storage::nor_flash::check_read(self, offset, bytes.len())?;
        if !self.powered {
            return Err(POWER_LOST);
        }
        bytes.copy_from_slice(&self.bytes[offset as usize..offset as usize + bytes.len()]);
        Ok(())
    }

    fn capacity(&self) -> usize {
        self.bytes.len()
    }
}

impl<const WRITE: usize, const ERASE: usize> NorFlash for CutFlash<WRITE, ERASE> {
    const WRITE_SIZE: usize = WRITE;
    const ERASE_SIZE: usize = ERASE;

    fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
        embedded_storage::nor_flash::check_erase(self, from, to)?;
        for sector in from as usize / ERASE..to as usize / ERASE {
            if !self.powered {
                return Err(POWER_LOST);
            }
            self.log.push((self.ops, Op::Erase { sector }));
            self.sector_erases[sector] += 1;
            for k in 0..ERASE {
                let step = if matches!(self.erase_cut, EraseCut::Descending) { ERASE - 1 - k } else { k };
                let a = sector * ERASE + step;
                if !self.take_op() {
                    self.tear_erase(sector, a);
                    return Err(POWER_LOST);
                }
                self.bytes[a] = 0xFF;
                self.programmed[a] = false;
            }
        }
        Ok(())
    }

    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
        embedded_storage::nor_flash::check_write(self, offset, bytes.len())?;
        if !self.powered {
            return Err(POWER_LOST);
        }
        self.log.push((self.ops, Op::Write { offset: offset as usize }));
        for (i, &b) in bytes.iter().enumerate() {
            let a = offset as usize + i;
            if !self.take_op() {
                // Some of the bits being cleared are cleared.
                self.bytes[a] &= b | self.random_byte(a);
                return Err(POWER_LOST);
            }
            self.double_writes += usize::from(self.programmed[a]);
            self.programmed[a] = true;
            self.bytes[a] &= b;
            self.bytes_programmed += 1;
        }
        Ok(())
    }
}

/// A random payload.
fn payload(len: usize, seed: u64) -> Vec<u8> {
    (0..len).map(|i| mix(seed.wrapping_mul(0x1_0000_0001) ^ i as u64) as u8).collect()
}

/// The newest record and its payload.
fn load<F: NorFlash>(store: &mut RecordStore<F>) -> Option<(RecordInfo, Vec<u8>)> {
    let info = store.newest().expect("the flash reads")?;
    let mut out = vec![0u8; info.len];
    store.read(&info, 0, &mut out).expect("the record reads");
    Some((info, out))
}

/// What a reboot after a cut found.
#[derive(Clone, Copy, PartialEq, Debug)]
enum Outcome {
    Old,
    New,
    None,
}

/// Outcome counts of the cuts within one phase of the store.
struct Row {
    label: String,
    first_op: usize,
    last_op: usize,
    counts: [usize; 3],
}

/// The store's phases from the log of an uncut store: every erase, the payload writes, the header write.
fn phases(log: &[(usize, Op)], total: usize, slot_bytes: usize) -> Vec<Row> {
    let mut rows: Vec<Row> = Vec::new();
    for (k, &(first, op)) in log.iter().enumerate() {
        let label = match op {
            Op::Erase { sector } => format!("erase of sector {sector}"),
            Op::Write { offset } if offset % slot_bytes == 0 => "header write".to_string(),
            Op::Write { .. } => "payload writes".to_string(),
        };
        let last = log.get(k + 1).map_or(total, |n| n.0) - 1;
        match rows.last_mut() {
            Some(r) if r.label == label => r.last_op = last,
            _ => rows.push(Row { label, first_op: first, last_op: last, counts: [0; 3] }),
        }
    }
    rows.push(Row { label: "none: the store completes".into(), first_op: total, last_op: total, counts: [0; 3] });
    rows
}

/// Every N of `rows` to cut at: all of them, or (with `stride`) all of the header write, the first and last 64
/// of every phase, and every `stride`-th elsewhere.
fn cut_points(rows: &[Row], stride: Option<usize>) -> Vec<usize> {
    let mut points = Vec::new();
    for r in rows {
        for n in r.first_op..=r.last_op {
            let near_edge = n < r.first_op + 64 || n + 64 > r.last_op;
            if stride.is_none_or(|s| r.label == "header write" || near_edge || n % s == 0) {
                points.push(n);
            }
        }
    }
    points
}

/// A store of `new` over the records already in `base` (`old`: the newest of them), cut at every planned N.
fn cut_every_byte<const W: usize, const E: usize>(
    title: &str,
    base: &CutFlash<W, E>,
    slot_bytes: u32,
    old: Option<(&RecordInfo, &[u8])>,
    new: &[u8],
    stride: Option<usize>,
) -> Vec<Row> {
    // The uncut store: its operations and their phases.
    let mut reference = base.clone();
    reference.log.clear();
    reference.ops = 0;
    let mut store = RecordStore::new(reference, slot_bytes).unwrap();
    let report = store.store_bytes(new).unwrap();
    let reference = store.release();
    let total = reference.ops;
    assert_eq!(reference.double_writes, 0, "{title}: a byte was programmed twice");
    let mut rows = phases(&reference.log, total, slot_bytes as usize);
    let old_sequence = old.map(|o| o.0.sequence);
    let new_sequence = old_sequence.map_or(FIRST_SEQUENCE, |s| s + 1);
    assert_eq!(report.sequence, new_sequence);
    let points = cut_points(&rows, stride);
    let started = std::time::Instant::now();
    for &n in &points {
        let mut flash = base.clone();
        let erase_cut = [EraseCut::Ascending, EraseCut::Descending, EraseCut::Garbage][n % 3];
        flash.cut_after(n, erase_cut, mix(n as u64 ^ 0xC0FFEE));
        let mut store = RecordStore::new(flash, slot_bytes).unwrap();
        let result = store.store_bytes(new);
        assert_eq!(result.is_ok(), n == total, "{title}: cut after {n} of {total} operations: {result:?}");
        // Reboot.
        let mut flash = store.release();
        flash.power_on();
        let mut store = RecordStore::new(flash, slot_bytes).unwrap();
        // A damaged newer record is reported only for a cut inside the header write (its CRC bytes torn), and
        // then it is the new record: a cut anywhere else leaves no whole header to report.
        let in_header = rows.iter().any(|r| r.label == "header write" && r.first_op <= n && n <= r.last_op);
        if let Some(d) = store.scan().unwrap().damaged_newer {
            assert!(in_header && d.sequence == new_sequence, "{title}: cut after {n}: damaged {d:?} reported");
        }
        let outcome = match load(&mut store) {
            None => {
                assert!(old.is_none(), "{title}: cut after {n}: the old record is lost");
                Outcome::None
            }
            Some((info, bytes)) if Some(info.sequence) == old_sequence => {
                assert!(old.is_some_and(|o| o.1 == bytes.as_slice()), "{title}: cut after {n}: old record corrupt");
                Outcome::Old
            }
            Some((info, bytes)) => {
                assert_eq!(info.sequence, new_sequence, "{title}: cut after {n}: unknown record");
                assert!(bytes == new, "{title}: cut after {n}: new record corrupt");
                Outcome::New
            }
        };
        if let Some(r) = rows.iter_mut().find(|r| r.first_op <= n && n <= r.last_op) {
            r.counts[outcome as usize] += 1;
        }
        // The store recovers: the next record goes in and loads.
        let next = &new[..new.len() / 2];
        store.store_bytes(next).unwrap_or_else(|e| panic!("{title}: store after the cut at {n}: {e}"));
        assert_eq!(load(&mut store).map(|l| l.1), Some(next.to_vec()), "{title}: after the cut at {n}");
        assert_eq!(store.release().double_writes, 0, "{title}: a byte was programmed twice");
    }
    print_table(title, total, points.len(), started.elapsed(), &rows);
    rows
}

fn print_table(title: &str, total: usize, cuts: usize, took: std::time::Duration, rows: &[Row]) {
    println!("\n{title}: {total} byte operations per store, {cuts} cuts, {:.2} s", took.as_secs_f64());
    println!("  {:<26} {:>15} {:>7} {:>7} {:>7} {:>7}", "cut during", "after N ops", "cuts", "old", "new", "none");
    for r in rows {
        let range = format!("{}..={}", r.first_op, r.last_op);
        let cuts: usize = r.counts.iter().sum();
        let [old, new, none] = r.counts;
        println!("  {:<26} {range:>15} {cuts:>7} {old:>7} {new:>7} {none:>7}", r.label);
    }
}

/// A flash with the given records stored in order; the newest and its payload.
fn with_records<const W: usize, const E: usize>(
    sectors: usize,
    slot_bytes: u32,
    records: &[Vec<u8>],
) -> (CutFlash<W, E>, Option<(RecordInfo, Vec<u8>)>) {
    let mut store = RecordStore::new(CutFlash::<W, E>::erased(sectors), slot_bytes).unwrap();
    for r in records {
        store.store_bytes(r).unwrap();
    }
    let newest = load(&mut store);
    (store.release(), newest)
}

/// A store over none, one and two records on one geometry: the table's counts per scenario.
fn three_scenarios<const W: usize, const E: usize>(
    geometry: &str,
    sectors: usize,
    slot_bytes: u32,
    len: usize,
    stride: Option<usize>,
) {
    let olds = [payload(len - 700, 1), payload(len - 300, 2)];
    let new = payload(len, 3);
    for existing in 0..=2 {
        let (base, newest) = with_records::<W, E>(sectors, slot_bytes, &olds[..existing]);
        let title = format!("{geometry}, store of {len} bytes over {existing} record(s)");
        let old = newest.as_ref().map(|(i, b)| (i, b.as_slice()));
        let rows = cut_every_byte(&title, &base, slot_bytes, old, &new, stride);
        let [old_count, new_count, none_count]: [usize; 3] =
            std::array::from_fn(|k| rows.iter().map(|r| r.counts[k]).sum());
        // A cut before the header write never shows the new record; the completed store always does.
        let before_header: usize = rows.iter().take_while(|r| r.label != "header write").map(|r| r.counts[1]).sum();
        assert_eq!(before_header, 0, "{title}: the new record showed before its header was written");
        assert_eq!(rows.last().unwrap().counts, [0, 1, 0], "{title}");
        if existing == 0 {
            assert_eq!(old_count, 0);
            assert!(none_count > 0 && new_count >= 1);
        } else {
            assert_eq!(none_count, 0);
            assert!(old_count > 0 && new_count >= 1);
        }
    }
}

#[test]
fn power_cut_at_every_byte_small_sectors_write_granule_1() {
    // Slots of two 512-byte sectors, a record of 900 bytes spanning both.
    three_scenarios::<1, 512>("512-byte sectors, write granule 1", 4, 1024, 900, None);
}

#[test]
fn power_cut_at_every_byte_small_sectors_write_granule_4() {
    // 901 bytes: the payload's last word is padded.
    three_scenarios::<4, 512>("512-byte sectors, write granule 4", 4, 1024, 901, None);
}

#[test]
fn power_cut_on_the_boards_geometry() {
    // Two 16-KiB sectors, one per slot, write granule 4; a 10,240-byte record.
    three_scenarios::<4, 16384>("16-KiB sectors, write granule 4", 2, 16384, 10_240, Some(23));
}

type Board = CutFlash<4, 16384>;

#[test]
fn erase_counts_per_store() {
    // The store borrows the flash (`&mut` of a NorFlash is one), so the flash's counters can be read between
    // stores; a new `RecordStore` does no flash operation.
    let mut flash = Board::erased(2);
    println!("\nerase counts per store (sector erases the store reports / the flash counted):");
    for (k, len) in [10_240, 16_364, 20, 0, 10_240].into_iter().enumerate() {
        let before: u32 = flash.sector_erases.iter().sum();
        let report = RecordStore::new(&mut flash, 16384).unwrap().store_bytes(&payload(len, k as u64)).unwrap();
        let counted = flash.sector_erases.iter().sum::<u32>() - before;
        println!("  16-KiB sectors, {len:>6}-byte record into slot {}: {} / {counted}", report.slot, report.erases);
        assert_eq!((report.erases, counted), (1, 1), "a record that fits one sector costs one erase");
    }
    let mut flash = CutFlash::<1, 512>::erased(4);
    for (len, expected) in [(900, 2), (400, 1), (492, 1), (493, 2), (1004, 2)] {
        let before: u32 = flash.sector_erases.iter().sum();
        let mut store = RecordStore::new(&mut flash, 1024).unwrap();
        let report = store.store_bytes(&payload(len, 9)).unwrap();
        assert_eq!(load(&mut store).unwrap().1, payload(len, 9));
        let counted = flash.sector_erases.iter().sum::<u32>() - before;
        println!("  two 512-byte sectors per slot, {len:>4}-byte record: {} / {counted}", report.erases);
        assert_eq!((report.erases, counted), (expected, expected), "{len} bytes");
    }
}

/// The newest of two records damaged after it was stored, one bit cleared (as NOR flash can lose it) at every
/// byte of its header and payload in turn, on the boards' geometry: the older record loads, bit for bit; the
/// damage is reported for every byte the CRC covers beyond the fields that make a header whole (a cleared bit
/// in the magic, version, payload offset or a sequence number made older leaves nothing newer to report); and
/// the next store goes into the damaged slot and loads.
#[test]
fn a_damaged_newest_record_falls_back_to_the_older_and_says_so() {
    let (old, new) = (payload(3000, 5), payload(4000, 6));
    let (base, newest) = with_records::<4, { 16 * 1024 }>(2, 16384, &[old.clone(), new.clone()]);
    assert_eq!(newest.map(|n| (n.0.slot, n.0.sequence)), Some((1, 2)));
    let (mut reported, mut silent) = (0, 0);
    for at in 16384..16384 + 20 + new.len() {
        let Some(bit) = (0..8).find(|b| base.bytes[at] & (1 << b) != 0) else { continue };
        let mut flash = base.clone();
        flash.bytes[at] &= !(1 << bit);
        let mut store = RecordStore::new(flash, 16384).unwrap();
        let (info, bytes) = load(&mut store).expect("the older record loads");
        assert_eq!((info.sequence, bytes == old), (1, true), "bit {bit} of byte {at} cleared");
        let scan = store.scan().unwrap();
        let field = at - 16384;
        match scan.damaged_newer {
            Some(d) => {
                assert_eq!(d.slot, 1);
                reported += 1;
            }
            None => {
                assert!(field < 12, "bit {bit} of byte {at} (header byte {field}): the damage was not reported");
                silent += 1;
            }
        }
        if at % 97 == 0 {
            let report = store.store_bytes(&payload(100, 7)).unwrap();
            assert_eq!((report.slot, report.sequence), (1, 2), "the next store replaces the damaged record");
            assert_eq!(load(&mut store).map(|l| l.1), Some(payload(100, 7)));
        }
    }
    println!("\na damaged newest record: reported for {reported} damaged bytes, silent for {silent} header bytes");
    assert!(reported >= new.len() * 9 / 10, "{reported}");
}

#[test]
fn erase_all_and_a_record_too_large() {
    let mut flash = Board::erased(2);
    let mut store = RecordStore::new(&mut flash, 16384).unwrap();
    assert_eq!(store.max_payload(), 16_384 - 20);
    store.store_bytes(&payload(100, 1)).unwrap();
    store.store_bytes(&payload(200, 2)).unwrap();
    let ops_before = (flash.ops, flash.bytes_programmed);
    // Too large: refused before any flash operation, the record intact.
    let mut store = RecordStore::new(&mut flash, 16384).unwrap();
    let refused = store.store(16_365, |_, _| panic!("the payload of a refused record is never asked for"));
    assert_eq!(refused, Err(StoreError::TooLarge { len: 16_365, max: 16_364 }));
    assert_eq!(load(&mut store).unwrap(), (RecordInfo { slot: 1, sequence: 2, len: 200 }, payload(200, 2)));
    assert_eq!((flash.ops, flash.bytes_programmed), ops_before, "a refused store touched the flash");
    // A full slot, streamed from a generator: the store never holds the payload.
    let byte = |i: usize| (i.wrapping_mul(7919) >> 3) as u8;
    let mut store = RecordStore::new(&mut flash, 16384).unwrap();
    let report = store
        .store(16_364, |offset, chunk| {
            chunk.iter_mut().enumerate().for_each(|(i, b)| *b = byte(offset + i));
            Ok(())
        })
        .unwrap();
    assert_eq!((report.slot, report.sequence, report.bytes_written), (0, 3, 16_384));
    let info = store.newest().unwrap().unwrap();
    let mut chunk = [0u8; 1000];
    for offset in (0..16_364).step_by(1000) {
        let n = chunk.len().min(16_364 - offset);
        store.read(&info, offset, &mut chunk[..n]).unwrap();
        assert!(chunk[..n].iter().enumerate().all(|(i, &b)| b == byte(offset + i)), "offset {offset}");
    }
    // Erase everything: two sector erases, no record, and the next store starts again at sequence 1 in slot 0.
    let erases_before: u32 = flash.sector_erases.iter().sum();
    let mut store = RecordStore::new(&mut flash, 16384).unwrap();
    assert_eq!(store.erase_all().unwrap(), 2);
    assert_eq!(store.newest().unwrap(), None);
    let report = store.store_bytes(&payload(10, 4)).unwrap();
    assert_eq!((report.slot, report.sequence), (0, FIRST_SEQUENCE));
    assert_eq!(flash.sector_erases.iter().sum::<u32>() - erases_before, 3, "erase_all's two and the store's one");
    println!("\nerase_all: 2 sector erases (16-KiB sectors); a 16,365-byte record refused, 16,364 bytes stored");
}

#[test]
fn wear_of_a_thousand_stores() {
    let mut store = RecordStore::new(Board::erased(2), 16384).unwrap();
    let record = payload(10_240, 5);
    for k in 0..1000u32 {
        let report = store.store_bytes(&record).unwrap();
        assert_eq!((report.slot, report.sequence), ((k % 2) as u8, k + 1), "store {k}");
    }
    assert_eq!(load(&mut store).unwrap().0, RecordInfo { slot: 1, sequence: 1000, len: 10_240 });
    let flash = store.release();
    println!(
        "\nwear: 1000 stores of a 10,240-byte record, 16-KiB sectors: sector erases {:?}, {} bytes programmed \
         ({} per store), {} bytes programmed twice",
        flash.sector_erases,
        flash.bytes_programmed,
        flash.bytes_programmed / 1000,
        flash.double_writes
    );
    assert_eq!(flash.sector_erases, vec![500, 500]);
    assert_eq!(flash.bytes_programmed, 1000 * (10_240 + 20));
    assert_eq!(flash.double_writes, 0);
}
