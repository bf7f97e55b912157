//! What a run may ask of the machine: a memory estimate is checked before anything is
//! allocated, so that a scenario too large for the machine is refused with the estimate and the
//! limit instead of aborting on an allocation.

use crate::ParamError;

/// Memory this process may plan to use: `MemAvailable` of /proc/meminfo (Linux; else 8 GiB),
/// or less when the process's address space is limited (`ulimit -v`: the limit less what is
/// mapped already). `COLLOIDSIM_MEMORY_LIMIT` (bytes, or with a suffix K, M, G, T of powers of
/// 1024: `4G`) overrides it (tests; batch systems with their own limit).
pub fn available_memory() -> f64 {
    if let Some(v) = std::env::var("COLLOIDSIM_MEMORY_LIMIT")
        .ok()
        .and_then(|v| parse_bytes(&v))
    {
        return v;
    }
    let field = |file: &str, name: &str, at: usize| -> Option<f64> {
        std::fs::read_to_string(file).ok().and_then(|s| {
            s.lines()
                .find(|l| l.starts_with(name))
                .and_then(|l| l.split_whitespace().nth(at))
                .and_then(|v| v.parse::<f64>().ok())
        })
    };
    let free = field("/proc/meminfo", "MemAvailable:", 1).map_or(8.0 * GIB, |kb| kb * 1024.0);
    // "Max address space   <soft> <hard> bytes"; "unlimited" does not parse.
    match field("/proc/self/limits", "Max address space", 3) {
        Some(limit) => {
            let mapped = field("/proc/self/status", "VmSize:", 1).map_or(0.0, |kb| kb * 1024.0);
            free.min((limit - mapped).max(0.0))
        }
        None => free,
    }
}

const GIB: f64 = 1024.0 * 1024.0 * 1024.0;

/// `4096`, `512M`, `4G`, `4GiB`, `1.5T` as bytes.
fn parse_bytes(text: &str) -> Option<f64> {
    let t = text.trim();
    let t = t
        .strip_suffix("iB")
        .or_else(|| t.strip_suffix('B'))
        .unwrap_or(t);
    let (number, scale) = match t.chars().last()? {
        'K' | 'k' => (&t[..t.len() - 1], 1024.0),
        'M' | 'm' => (&t[..t.len() - 1], 1024.0 * 1024.0),
        'G' | 'g' => (&t[..t.len() - 1], GIB),
        'T' | 't' => (&t[..t.len() - 1], 1024.0 * GIB),
        _ => (t, 1.0),
    };
    let v = number.trim().parse::<f64>().ok()? * scale;
    (v.is_finite() && v >= 0.0).then_some(v)
}

/// Bytes as a person reads them.
pub fn human(bytes: f64) -> String {
    if !bytes.is_finite() {
        return format!("{bytes} B");
    }
    let units = ["B", "KiB", "MiB", "GiB", "TiB", "PiB"];
    let mut v = bytes;
    let mut u = 0;
    while v >= 1024.0 && u + 1 < units.len() {
        v /= 1024.0;
        u += 1;
    }
    if u + 1 == units.len() && v >= 1024.0 {
        return format!("{:.1e} B", bytes);
    }
    format!("{v:.1} {}", units[u])
}

/// Refuse `bytes` (an estimate of what `what` needs) when it exceeds 80 % of the memory
/// available; the error names `key`, the estimate and the limit.
pub fn ensure_fits(key: &str, what: &str, bytes: f64) -> Result<(), ParamError> {
    let limit = 0.8 * available_memory();
    if !bytes.is_finite() {
        Err(ParamError::new(
            key,
            format!("{what} has no finite size: no machine can hold it"),
        ))
    } else if bytes <= limit {
        Ok(())
    } else {
        Err(ParamError::new(
            key,
            format!(
                "{what} would need about {}, more than this machine can give ({} available)",
                human(bytes),
                human(limit)
            ),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn estimates_beyond_the_limit_are_refused_naming_the_key() {
        assert!(ensure_fits("system.particles", "10 rods", 1e3).is_ok());
        let e = ensure_fits("system.particles", "1e18 rods", 6.4e19).unwrap_err();
        assert_eq!(e.key, "system.particles");
        assert!(
            e.message.contains("1e18 rods") && e.message.contains("6.4e19 B"),
            "{e}"
        );
        assert!(ensure_fits("k", "x", f64::INFINITY).is_err());
        assert!(ensure_fits("k", "x", f64::NAN).is_err());
        assert_eq!(human(1536.0), "1.5 KiB");
    }

    #[test]
    fn memory_limits_are_read_with_their_unit() {
        assert_eq!(parse_bytes("4096"), Some(4096.0));
        assert_eq!(parse_bytes("512M"), Some(512.0 * 1024.0 * 1024.0));
        assert_eq!(parse_bytes(" 4G "), Some(4.0 * GIB));
        assert_eq!(parse_bytes("4GiB"), Some(4.0 * GIB));
        assert_eq!(parse_bytes("1.5T"), Some(1.5 * 1024.0 * GIB));
        for bad in ["", "G", "-1G", "four", "nan", "infG"] {
            assert_eq!(parse_bytes(bad), None, "{bad}");
        }
    }
}
