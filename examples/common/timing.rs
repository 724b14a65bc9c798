//! Timing shared by the kernel benchmarks: best wall-clock and on-CPU
//! time of repeated calls.

use std::time::Instant;

/// Best wall-clock time and best on-CPU time (s) of `reps` calls of `run`.
pub fn time_best(reps: usize, mut run: impl FnMut()) -> (f64, Option<f64>) {
    let (mut best, mut cpu) = (f64::MAX, None::<f64>);
    for _ in 0..reps {
        let (t0, c0) = (Instant::now(), thread_cpu_time());
        run();
        best = best.min(t0.elapsed().as_secs_f64());
        if let (Some(c0), Some(c1)) = (c0, thread_cpu_time()) {
            cpu = Some(cpu.map_or(c1 - c0, |c| c.min(c1 - c0)));
        }
    }
    (best, cpu)
}

/// Time this thread has spent on a CPU (s), from
/// `clock_gettime(CLOCK_THREAD_CPUTIME_ID)` (ns resolution); `None` off 64-bit Linux.
#[cfg(all(target_os = "linux", target_pointer_width = "64"))]
pub fn thread_cpu_time() -> Option<f64> {
    #[repr(C)]
    struct Timespec {
        sec: i64,
        nsec: i64,
    }
    extern "C" {
        fn clock_gettime(clock: i32, ts: *mut Timespec) -> i32;
    }
    const CLOCK_THREAD_CPUTIME_ID: i32 = 3;
    let mut ts = Timespec { sec: 0, nsec: 0 };
    // SAFETY: `ts` is a valid, writable timespec (two 64-bit fields on 64-bit Linux).
    let rc = unsafe { clock_gettime(CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    (rc == 0).then_some(ts.sec as f64 + ts.nsec as f64 * 1e-9)
}

#[cfg(not(all(target_os = "linux", target_pointer_width = "64")))]
pub fn thread_cpu_time() -> Option<f64> {
    None
}
