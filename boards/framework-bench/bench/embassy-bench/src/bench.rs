//! Common part of the embassy benches: a task on embassy-executor's thread-mode executor
//! awaits a data-ready future woken from the EXTI0 interrupt, which is pended by software
//! N times.
//!
//! embassy_stm32::init cannot run under QEMU (its clock setup spins on RCC ready flags),
//! and QEMU's EXTI model never sets PR for a software trigger, so this MODELS
//! embassy-stm32 0.6's ExtiInput: same embassy-sync AtomicWaker, same "armed" protocol
//! (ExtiInput's future unmasks the EXTI IMR bit; the IRQ masks it and wakes; the future is
//! Ready once the bit is masked). The `ExtiLine` impl of each binary decides how much of
//! ExtiInput's register work is replicated.

use core::future::Future;
use core::pin::Pin;
use core::task::{Context, Poll};
use embassy_sync::waitqueue::AtomicWaker;

pub static DRDY_WAKER: AtomicWaker = AtomicWaker::new();

/// What ExtiInput does to the EXTI line per edge.
pub trait ExtiLine {
    /// ExtiInputFuture::new: configure edge, clear pending, unmask IMR.
    fn arm();
    /// ExtiInputFuture::poll's readiness check: IMR bit already masked by the IRQ?
    fn fired() -> bool;
    /// ExtiInputFuture::drop: mask IMR.
    fn disarm();
    /// exti::on_irq: read PR, mask fired lines, wake, clear PR.
    fn on_irq();
    /// One-time setup before the measurement.
    fn setup() {}
}

/// Model of the future of `ExtiInput::wait_for_rising_edge()`.
pub struct DataReady<L: ExtiLine>(core::marker::PhantomData<L>);

impl<L: ExtiLine> DataReady<L> {
    pub fn new() -> Self {
        L::arm();
        DataReady(core::marker::PhantomData)
    }
}

impl<L: ExtiLine> Future for DataReady<L> {
    type Output = ();
    fn poll(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<()> {
        DRDY_WAKER.register(cx.waker());
        if L::fired() {
            Poll::Ready(())
        } else {
            Poll::Pending
        }
    }
}

impl<L: ExtiLine> Drop for DataReady<L> {
    fn drop(&mut self) {
        L::disarm();
    }
}

/// Defines the EXTI0 handler, the bench task and `main` for one `ExtiLine` impl.
#[macro_export]
macro_rules! embassy_bench {
    ($name:literal, $line:ty) => {
        use bench_common::*;
        use cortex_m::peripheral::NVIC;
        use embassy_executor::raw;
        use stm32f4::stm32f405::{interrupt, Interrupt};

        #[interrupt]
        fn EXTI0() {
            <$line as ExtiLine>::on_irq();
        }

        #[embassy_executor::task]
        async fn bench_task(cal: Calibration, direct_ticks: u32) {
            let t0 = now_ticks();
            for _ in 0..N_SAMPLES {
                DataReady::<$line>::new().await;
                sample_work();
            }
            let ticks = elapsed_ticks(t0, now_ticks());
            print_result($name, "task", &cal, N_SAMPLES, direct_ticks, ticks);
            let ok = samples_done() == 2 * N_SAMPLES;
            semihosting::println!("{} check: sample_work_calls={} ok={}", $name, samples_done(), ok);
            exit(ok)
        }

        #[cortex_m_rt::entry]
        fn main() -> ! {
            let mut cp = cortex_m::Peripherals::take().unwrap();
            start_systick(&mut cp.SYST);
            let cal = calibrate();
            print_calibration($name, &cal);
            let direct_ticks = direct_loop_ticks(N_SAMPLES);

            <$line as ExtiLine>::setup();
            unsafe { NVIC::unmask(Interrupt::EXTI0) };

            // Same executor and pender as embassy_executor::Executor (thread mode: pender =
            // SEV, context usize::MAX), driven by the same `poll(); wfe` loop as
            // Executor::run, except that the data-ready edge is injected before the WFE.
            let executor = raw::Executor::new(usize::MAX as *mut ());
            // SAFETY: main never returns, so the executor lives forever.
            let executor: &'static raw::Executor = unsafe { core::mem::transmute(&executor) };
            executor.spawner().spawn(bench_task(cal, direct_ticks).unwrap());
            loop {
                unsafe { executor.poll() };
                NVIC::pend(Interrupt::EXTI0); // stand-in for the sensor's data-ready edge
                cortex_m::asm::wfe();
            }
        }
    };
}
