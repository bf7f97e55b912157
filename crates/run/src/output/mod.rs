//! The writers every session shares: the GSD trajectory (its opener, frame digest and trim on
//! restart: [`trajectory`]), pictures ([`plot`]) and the drying droplet's profile names (of
//! droplet-bd, its theory and droplet-mpcd). Tables, thermo logs (`CsvLog`), JSON and the
//! atomic writes under them, with the rule that every number is finite or empty with its
//! reason, are `colloidsim_core::output`'s, which the engine crates use too.

pub mod plot;
pub mod species;
pub mod trajectory;

/// File name of the profile at `fraction` of the drying time: `profile_0.25.csv` (two decimals,
/// more when the fraction needs them).
pub fn profile_name(fraction: f64) -> String {
    if ((fraction * 100.0).round() - fraction * 100.0).abs() < 1e-9 {
        format!("profile_{fraction:.2}.csv")
    } else {
        format!("profile_{fraction}.csv")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn profile_names_match_the_fractions() {
        assert_eq!(profile_name(0.0), "profile_0.00.csv");
        assert_eq!(profile_name(0.25), "profile_0.25.csv");
        assert_eq!(profile_name(1.0), "profile_1.00.csv");
        assert_eq!(profile_name(0.125), "profile_0.125.csv");
    }
}
