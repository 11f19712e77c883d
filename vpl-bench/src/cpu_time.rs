//! The CPU time this process has used: a cost that does not move with the
//! machine's load the way wall time does (other processes take cores, not
//! CPU seconds), for efficiencies such as Georgiev's 1 / (MSE · cost).

/// CPU seconds of this process so far, all threads: the sum of the
/// nanosecond run times of its live threads (`/proc/self/task/*/schedstat`,
/// field 1), or, where those are missing, user plus system time from
/// `/proc/self/stat` (fields 14 and 15, in USER_HZ = 100 ticks a second, fixed
/// for `/proc` on Linux). `None` where neither can be read. Threads that have
/// exited drop out of the first sum, so measure with a thread pool that
/// outlives the interval (rayon's does).
pub fn process_cpu_seconds() -> Option<f64> {
    threads_cpu_seconds().or_else(ticks_cpu_seconds)
}

fn threads_cpu_seconds() -> Option<f64> {
    let mut ns = 0u64;
    let mut any = false;
    for task in std::fs::read_dir("/proc/self/task").ok()?.flatten() {
        // A thread may exit between the listing and the read.
        let Ok(text) = std::fs::read_to_string(task.path().join("schedstat")) else { continue };
        ns += text.split_whitespace().next()?.parse::<u64>().ok()?;
        any = true;
    }
    any.then_some(ns as f64 * 1e-9)
}

fn ticks_cpu_seconds() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/self/stat").ok()?;
    // The command name (field 2) is in parentheses and may hold spaces.
    let rest = &text[text.rfind(')')? + 1..];
    let fields: Vec<&str> = rest.split_whitespace().collect();
    // `rest` starts at field 3 (state): utime is field 14, stime field 15.
    let utime: u64 = fields.get(11)?.parse().ok()?;
    let stime: u64 = fields.get(12)?.parse().ok()?;
    Some((utime + stime) as f64 / 100.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn live_threads_never_exceed_the_process_total() {
        // Read the total after the threads' sum: it also holds exited threads'
        // time and whatever ran between the reads; 0.05 s covers its 10 ms ticks.
        if let (Some(a), Some(b)) = (threads_cpu_seconds(), ticks_cpu_seconds()) {
            assert!(a <= b + 0.05, "threads {a} s, process {b} s");
        }
    }

    #[test]
    fn cpu_time_grows_with_work() {
        let Some(t0) = process_cpu_seconds() else { return };
        // Work until the counter has advanced 0.1 s (other test threads may add
        // to it; they cannot take it back), giving up after 20 s of wall time.
        let start = std::time::Instant::now();
        let mut x = 1u64;
        let mut used = 0.0;
        while used < 0.1 && start.elapsed().as_secs_f64() < 20.0 {
            for i in 0..100_000u64 {
                x = x.wrapping_mul(6364136223846793005).wrapping_add(i);
            }
            used = process_cpu_seconds().unwrap() - t0;
        }
        std::hint::black_box(x);
        assert!(used >= 0.1, "20 s of spinning used only {used} s of CPU");
    }
}
