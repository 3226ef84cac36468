//! The calibration record's flash: sectors 1 and 2 of the STM32F405's flash (0x0800_4000, 2 x 16 KiB, reserved in
//! memory.x) as an embedded-storage `NorFlash`, for the core's power-safe A/B record store (one slot per sector).
//!
//! Register sequence (RM0090, "Embedded Flash memory interface"): unlock with the two keys of KEYR; program with
//! PSIZE = x32 (needs a 2.7 to 3.6 V supply) and PG set, one aligned 32-bit word per store; erase a sector with SER,
//! SNB and STRT; wait while SR.BSY; check the error flags (PGSERR, PGPERR, PGAERR, WRPERR, OPERR) and clear them
//! (write 1); lock again. The ART accelerator's caches are reset after every operation, as ST's own driver does, so
//! that no stale line of an erased or programmed address is read back.
//!
//! A sector erase stalls every fetch from flash, interrupts included, for 250 ms typical and 500 ms at most at x32
//! (data sheet): the watchdog is widened around it ([`crate::watchdog::widen`]). The store runs only after a solution
//! or on a request, never during a dwell.

use embedded_storage::nor_flash::{ErrorType, NorFlash, NorFlashError, NorFlashErrorKind, ReadNorFlash};
use stm32f4xx_hal::pac;

use crate::clocks::{cycles_now, us_since};
use crate::watchdog;

/// The record's first byte (sector 1).
pub const RECORD_BASE: u32 = 0x0800_4000;
/// Bytes of one sector of the record (sectors 1 and 2 are 16 KiB each).
pub const SECTOR_BYTES: u32 = 16 * 1024;
/// The sectors of the record, in address order.
pub const RECORD_SECTORS: [u8; 2] = [1, 2];
/// Bytes of the record's flash.
pub const CAPACITY_BYTES: u32 = SECTOR_BYTES * RECORD_SECTORS.len() as u32;

const KEY1: u32 = 0x4567_0123;
const KEY2: u32 = 0xCDEF_89AB;
/// CR: PG (bit 0), SER (bit 1), SNB (bits 3 to 6), PSIZE x32 (0b10 at bits 8 and 9), STRT (bit 16), LOCK (bit 31).
const CR_PG: u32 = 1 << 0;
const CR_SER: u32 = 1 << 1;
const CR_SNB_SHIFT: u32 = 3;
const CR_PSIZE_X32: u32 = 0b10 << 8;
const CR_STRT: u32 = 1 << 16;
const CR_LOCK: u32 = 1 << 31;
/// SR: EOP (bit 0), OPERR (1), WRPERR (4), PGAERR (5), PGPERR (6), PGSERR (7), BSY (16).
const SR_ERRORS: u32 = (1 << 1) | (1 << 4) | (1 << 5) | (1 << 6) | (1 << 7);
const SR_EOP: u32 = 1 << 0;
const SR_BSY: u32 = 1 << 16;
/// ACR: ICEN (9), DCEN (10), ICRST (11), DCRST (12).
const ACR_ICEN: u32 = 1 << 9;
const ACR_DCEN: u32 = 1 << 10;
const ACR_ICRST: u32 = 1 << 11;
const ACR_DCRST: u32 = 1 << 12;
/// Polls of SR.BSY after a word: programming takes 100 us at most (16 800 cycles at 168 MHz); a poll is at least a
/// cycle, so this bound is at least ten times that.
const PROGRAM_WAIT_POLLS: u32 = 200_000;
/// Polls of SR.BSY after a sector erase: 500 ms at most (84 million cycles); the bound is at least twice that.
const ERASE_WAIT_POLLS: u32 = 200_000_000;

/// What a flash operation can fail with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
pub enum FlashError {
    /// An offset or length not a multiple of the write or erase granule.
    NotAligned,
    /// Beyond the record's two sectors.
    OutOfBounds,
    /// The flash interface reported an error: the SR error bits.
    Interface {
        /// SR & (PGSERR | PGPERR | PGAERR | WRPERR | OPERR).
        sr_errors: u32,
    },
    /// BSY did not clear within the bound.
    Timeout,
}

impl NorFlashError for FlashError {
    fn kind(&self) -> NorFlashErrorKind {
        match self {
            FlashError::NotAligned => NorFlashErrorKind::NotAligned,
            FlashError::OutOfBounds => NorFlashErrorKind::OutOfBounds,
            FlashError::Interface { .. } | FlashError::Timeout => NorFlashErrorKind::Other,
        }
    }
}

/// Sectors 1 and 2; owns the flash interface.
pub struct RecordFlash {
    _flash: pac::FLASH,
}

extern "C" {
    static _record_start: u8;
    static _record_end: u8;
}

impl RecordFlash {
    /// The record's flash. `None` if memory.x reserves other addresses than [`RECORD_BASE`] and
    /// [`CAPACITY_BYTES`] (the two must describe the same sectors).
    pub fn new(flash: pac::FLASH) -> Option<RecordFlash> {
        // SAFETY: only the addresses of the linker's symbols are taken, never their contents.
        let (start, end) = unsafe { (&_record_start as *const u8 as u32, &_record_end as *const u8 as u32) };
        (start == RECORD_BASE && end - start == CAPACITY_BYTES).then_some(RecordFlash { _flash: flash })
    }

    fn regs() -> &'static pac::flash::RegisterBlock {
        // SAFETY: `RecordFlash` owns the FLASH peripheral; its registers are accessed only here (and by the
        // clock setup at boot, before).
        unsafe { &*pac::FLASH::ptr() }
    }

    fn check(offset: u32, len: usize, granule: u32) -> Result<(), FlashError> {
        if offset % granule != 0 || len as u32 % granule != 0 {
            return Err(FlashError::NotAligned);
        }
        match offset.checked_add(len as u32) {
            Some(end) if end <= CAPACITY_BYTES => Ok(()),
            _ => Err(FlashError::OutOfBounds),
        }
    }

    fn unlock() {
        let f = Self::regs();
        if f.cr().read().bits() & CR_LOCK != 0 {
            // SAFETY: the documented key sequence.
            f.keyr().write(|w| unsafe { w.bits(KEY1) });
            f.keyr().write(|w| unsafe { w.bits(KEY2) });
        }
        // Errors of an earlier operation would block this one: clear them (write 1 to clear).
        // SAFETY: only the error and EOP bits are written.
        f.sr().write(|w| unsafe { w.bits(SR_ERRORS | SR_EOP) });
    }

    fn lock() {
        // SAFETY: LOCK alone; PG, SER and STRT cleared.
        Self::regs().cr().write(|w| unsafe { w.bits(CR_LOCK) });
        Self::reset_caches();
    }

    /// Waits for BSY to clear (at most `polls` reads of SR), then checks the error flags.
    fn wait(polls: u32) -> Result<(), FlashError> {
        let f = Self::regs();
        for _ in 0..polls {
            let sr = f.sr().read().bits();
            if sr & SR_BSY == 0 {
                let sr_errors = sr & SR_ERRORS;
                return if sr_errors == 0 { Ok(()) } else { Err(FlashError::Interface { sr_errors }) };
            }
        }
        Err(FlashError::Timeout)
    }

    /// Resets the ART accelerator's instruction and data caches (each must be disabled while it is reset).
    fn reset_caches() {
        let f = Self::regs();
        let acr = f.acr().read().bits();
        // SAFETY: only the cache enable and reset bits change; the latency and prefetch bits are kept.
        f.acr().write(|w| unsafe { w.bits(acr & !(ACR_ICEN | ACR_DCEN)) });
        f.acr().write(|w| unsafe { w.bits((acr & !(ACR_ICEN | ACR_DCEN)) | ACR_ICRST | ACR_DCRST) });
        f.acr().write(|w| unsafe { w.bits(acr & !(ACR_ICRST | ACR_DCRST)) });
    }
}

impl ErrorType for RecordFlash {
    type Error = FlashError;
}

impl ReadNorFlash for RecordFlash {
    const READ_SIZE: usize = 1;

    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), FlashError> {
        Self::check(offset, bytes.len(), 1)?;
        for (i, b) in bytes.iter_mut().enumerate() {
            // SAFETY: the address lies in the record's sectors (checked above), which are always readable.
            *b = unsafe { core::ptr::read_volatile((RECORD_BASE + offset + i as u32) as *const u8) };
        }
        Ok(())
    }

    fn capacity(&self) -> usize {
        CAPACITY_BYTES as usize
    }
}

impl NorFlash for RecordFlash {
    const WRITE_SIZE: usize = 4;
    const ERASE_SIZE: usize = SECTOR_BYTES as usize;

    fn erase(&mut self, from: u32, to: u32) -> Result<(), FlashError> {
        if to < from {
            return Err(FlashError::OutOfBounds);
        }
        Self::check(from, (to - from) as usize, SECTOR_BYTES)?;
        Self::unlock();
        watchdog::widen();
        let mut result = Ok(());
        for k in from / SECTOR_BYTES..to / SECTOR_BYTES {
            let snb = (RECORD_SECTORS[k as usize] as u32) << CR_SNB_SHIFT;
            // SAFETY: a sector erase of one of the record's sectors at x32.
            Self::regs().cr().write(|w| unsafe { w.bits(CR_PSIZE_X32 | CR_SER | snb) });
            let start = cycles_now();
            Self::regs().cr().write(|w| unsafe { w.bits(CR_PSIZE_X32 | CR_SER | snb | CR_STRT) });
            result = Self::wait(ERASE_WAIT_POLLS);
            watchdog::feed();
            // A bring-up reading (docs/board.md#bring-up-checklist): 250 ms typical, 500 ms at most.
            defmt::info!("flash: sector {=u8} erased in {=u32} us", RECORD_SECTORS[k as usize], us_since(start));
            if result.is_err() {
                break;
            }
        }
        Self::lock();
        watchdog::restore();
        result
    }

    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), FlashError> {
        Self::check(offset, bytes.len(), 4)?;
        Self::unlock();
        // SAFETY: programming at x32.
        Self::regs().cr().write(|w| unsafe { w.bits(CR_PSIZE_X32 | CR_PG) });
        let mut result = Ok(());
        for (i, word) in bytes.chunks_exact(4).enumerate() {
            let address = RECORD_BASE + offset + 4 * i as u32;
            let value = u32::from_le_bytes([word[0], word[1], word[2], word[3]]);
            // SAFETY: an aligned word of the record's sectors, with PG set.
            unsafe { core::ptr::write_volatile(address as *mut u32, value) };
            result = Self::wait(PROGRAM_WAIT_POLLS);
            if result.is_err() {
                break;
            }
        }
        Self::lock();
        result
    }
}
