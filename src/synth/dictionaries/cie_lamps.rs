//! The camera-independent night-lamp dictionary: chromaticities of real lamps in CIE 1931
//! xy (2 degree observer) and the weights that make them a night-scene mix.
//!
//! Figures: CIE 015:2018, *Colorimetry*, 4th edition, the colorimetric data of the CIE
//! illuminants (Tables 9.x/10.x): illuminant A, the high-pressure discharge lamps HP1-HP5,
//! the LED illuminants LED-B1..B5, LED-BH1, LED-RGB1, LED-V1, LED-V2, the fluorescent
//! illuminants FL1-FL12 and FL3.1-FL3.15. Cross-checked against colour-science 0.4.7
//! (`colour.CCS_ILLUMINANTS['CIE 1931 2 Degree Standard Observer']`) by the validator test
//! `synth_lamps::cie_table_matches_colour_science`.
//!
//! Weights (docs/synthesis.md, "Night lamps in CIE xy"): integer counts of a notional
//! 45-card night session like the paper's (its 45 gray cards under street lights,
//! incandescent, fluorescent and LED light): high-pressure sodium 16 (HP1 10, HP2 6), metal
//! halide 5 (HP3 3, HP4 1, HP5 1), incandescent 7 (A), warm LED 7 (LED-B1 2, LED-B2 2,
//! LED-BH1, LED-RGB1, LED-V1 1 each), cool LED street lights 2 (LED-B3, LED-V2), warm
//! fluorescent 6 (FL4, FL12, FL3.1, FL3.4, FL3.7, FL3.12), white fluorescent 2 (FL3, FL11).
//! Daylight-type lamps (about 4,500 K and above) and duplicates of the same colour have weight
//! 0: they are in the table for reference and for xy dictionaries that name them.

/// Attribution of the lamp chromaticities.
pub const ATTRIBUTION: &str = "CIE 015:2018 Colorimetry, 4th ed., Tables 9.x/10.x \
(CIE 1931 2 degree observer); cross-checked with colour-science 0.4.7";

/// Name of the embedded night-lamp dictionary (messages, sidecars).
pub const NAME: &str = "CIE 015:2018 night lamps";

/// A lamp: CIE name, CIE 1931 xy and its weight in the night dictionary (0 = not used).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lamp {
    /// CIE 015:2018 name (`A`, `HP1`, `LED-B1`, `FL3.1`...).
    pub name: &'static str,
    /// What it is.
    pub kind: &'static str,
    /// CIE 1931 xy (2 degree observer).
    pub xy: [f64; 2],
    /// Weight in the default night dictionary (a count out of 45; 0 = not used).
    pub weight: f64,
}

const fn lamp(name: &'static str, kind: &'static str, xy: [f64; 2], weight: f64) -> Lamp {
    Lamp {
        name,
        kind,
        xy,
        weight,
    }
}

const HPS: &str = "high-pressure sodium";
const MH: &str = "metal halide";
const LED: &str = "LED";
const FL: &str = "fluorescent";

/// The CIE 015:2018 lamps (CCT and Duv in the comments: Ohno 2013, colour-science).
pub const LAMPS: [Lamp; 42] = [
    lamp("A", "incandescent (tungsten)", [0.44758, 0.40745], 7.0), // 2855 K, +0.0000
    lamp("HP1", HPS, [0.5330, 0.4150], 10.0),                      // 1959 K, +0.0008
    lamp(
        "HP2",
        "colour-enhanced high-pressure sodium",
        [0.4778, 0.4158],
        6.0,
    ), // 2506 K, +0.0007
    lamp("HP3", MH, [0.4302, 0.4075], 3.0),                        // 3144 K, +0.0024
    lamp("HP4", MH, [0.3812, 0.3797], 1.0),                        // 4001 K, +0.0012
    lamp("HP5", MH, [0.3776, 0.3713], 1.0),                        // 4039 K, -0.0017
    lamp("LED-B1", LED, [0.4560, 0.4078], 2.0),                    // 2733 K, -0.0007
    lamp("LED-B2", LED, [0.4357, 0.4012], 2.0),                    // 2997 K, -0.0010
    lamp("LED-B3", LED, [0.3756, 0.3723], 1.0),                    // 4103 K, -0.0007
    lamp("LED-B4", LED, [0.3422, 0.3502], 0.0),                    // 5108 K, +0.0005
    lamp("LED-B5", LED, [0.3118, 0.3236], 0.0),                    // 6598 K, +0.0009
    lamp("LED-BH1", LED, [0.4474, 0.4066], 1.0),                   // 2851 K, -0.0003
    lamp("LED-RGB1", LED, [0.4557, 0.4211], 1.0),                  // 2840 K, +0.0043
    lamp("LED-V1", LED, [0.4548, 0.4044], 1.0),                    // 2723 K, -0.0019
    lamp("LED-V2", LED, [0.3781, 0.3775], 1.0),                    // 4070 K, +0.0010
    lamp("FL1", FL, [0.3131, 0.3371], 0.0),                        // 6426 K, +0.0071
    lamp("FL2", FL, [0.3721, 0.3751], 0.0),                        // 4223 K, +0.0018
    lamp("FL3", FL, [0.4091, 0.3941], 1.0),                        // 3446 K, +0.0007
    lamp("FL4", FL, [0.4402, 0.4031], 1.0),                        // 2938 K, -0.0008
    lamp("FL5", FL, [0.3138, 0.3452], 0.0),                        // 6343 K, +0.0107
    lamp("FL6", FL, [0.3779, 0.3882], 0.0),                        // 4148 K, +0.0060
    lamp("FL7", FL, [0.3129, 0.3292], 0.0),                        // 6492 K, +0.0032
    lamp("FL8", FL, [0.3458, 0.3586], 0.0),                        // 4997 K, +0.0032
    lamp("FL9", FL, [0.3741, 0.3727], 0.0),                        // 4149 K, +0.0000
    lamp("FL10", FL, [0.3458, 0.3588], 0.0),                       // 4998 K, +0.0033
    lamp("FL11", FL, [0.3805, 0.3769], 1.0),                       // 4000 K, +0.0001
    lamp("FL12", FL, [0.4370, 0.4042], 1.0),                       // 3000 K, +0.0000
    lamp("FL3.1", FL, [0.4407, 0.4033], 1.0),                      // 2931 K, -0.0008
    lamp("FL3.2", FL, [0.3808, 0.3734], 0.0),                      // 3965 K, -0.0017
    lamp("FL3.3", FL, [0.3153, 0.3439], 0.0),                      // 6279 K, +0.0094
    lamp("FL3.4", FL, [0.4429, 0.4043], 1.0),                      // 2904 K, -0.0007
    lamp("FL3.5", FL, [0.3749, 0.3672], 0.0),                      // 4086 K, -0.0029
    lamp("FL3.6", FL, [0.3488, 0.3600], 0.0),                      // 4894 K, +0.0027
    lamp("FL3.7", FL, [0.4384, 0.4045], 1.0),                      // 2979 K, -0.0000
    lamp("FL3.8", FL, [0.3820, 0.3832], 0.0),                      // 4005 K, +0.0025
    lamp("FL3.9", FL, [0.3499, 0.3591], 0.0),                      // 4851 K, +0.0018
    lamp("FL3.10", FL, [0.3455, 0.3560], 0.0),                     // 5000 K, +0.0020
    lamp("FL3.11", FL, [0.3245, 0.3434], 0.0),                     // 5853 K, +0.0048
    lamp("FL3.12", FL, [0.4377, 0.4037], 1.0),                     // 2984 K, -0.0003
    lamp("FL3.13", FL, [0.3830, 0.3724], 0.0),                     // 3897 K, -0.0028
    lamp("FL3.14", FL, [0.3447, 0.3609], 0.0),                     // 5045 K, +0.0048
    lamp("FL3.15", FL, [0.3127, 0.3288], 0.0),                     // 6506 K, +0.0031
];

/// A lamp of [`LAMPS`] by its CIE name (case-insensitive).
pub fn by_name(name: &str) -> Option<&'static Lamp> {
    LAMPS
        .iter()
        .find(|l| l.name.eq_ignore_ascii_case(name.trim()))
}

/// The default night dictionary: the lamps of non-zero weight.
pub fn night_lamps() -> impl Iterator<Item = &'static Lamp> {
    LAMPS.iter().filter(|l| l.weight > 0.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::color::planck::cct_duv;

    #[test]
    fn the_night_mix_is_a_45_card_session_of_night_lamps() {
        let total: f64 = night_lamps().map(|l| l.weight).sum();
        assert_eq!(total, 45.0);
        let mut names: Vec<&str> = LAMPS.iter().map(|l| l.name).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), LAMPS.len(), "unique names");
        for l in night_lamps() {
            let (cct, duv) = cct_duv(l.xy).unwrap();
            // night lamps: warm to neutral white, on the locus
            assert!((1900.0..=4200.0).contains(&cct), "{} {cct}", l.name);
            assert!(duv.abs() < 0.005, "{} {duv}", l.name);
        }
        // every lamp of the table is a white near the locus
        for l in &LAMPS {
            let (_, duv) = cct_duv(l.xy).unwrap();
            assert!(duv.abs() < 0.011, "{} {duv}", l.name);
        }
        assert_eq!(by_name("fl3.12").map(|l| l.xy), Some([0.4377, 0.4037]));
        assert!(by_name("D65").is_none());
    }
}
