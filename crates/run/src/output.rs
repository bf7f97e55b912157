//! Names and writers that several methods share (the drying droplet's profile files of
//! droplet-bd, its theory and droplet-mpcd). The trajectory lives in [`crate::trajectory`],
//! pictures in [`crate::plot`], atomic tables in `colloidsim_core::output`.

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
