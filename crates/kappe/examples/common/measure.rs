//! What the timing examples print next to their wall times, so figures taken on a shared
//! machine can be read: the process's CPU time and the load average (Linux `/proc`).

/// User + system CPU time of this process, s (`/proc/self/stat` fields 14 and 15, clock ticks
/// of 1/100 s); `None` where `/proc` is not available.
pub fn cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // The fields after the command name, which is in parentheses and may hold spaces.
    let rest = stat.rsplit_once(')')?.1;
    let f: Vec<f64> = rest
        .split_whitespace()
        .skip(11)
        .take(2)
        .filter_map(|v| v.parse().ok())
        .collect();
    (f.len() == 2).then(|| f.iter().sum::<f64>() / 100.0)
}

/// The 1-minute load average (`/proc/loadavg`), as text (`?` where unknown).
pub fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|s| s.split_whitespace().next().map(str::to_string))
        .unwrap_or_else(|| "?".into())
}
