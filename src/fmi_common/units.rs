//! The units this FMU may declare and their SI base-unit exponents, written as
//! `<Unit><BaseUnit .../></Unit>` in `<UnitDefinitions>` (FMI 2.0 standard, section 2.2.2).
//! Angles use the `rad` exponent the standard provides, so `rad` and `1` stay distinguishable
//! and e.g. `N.m/rad` times `rad` is `N.m`. All units here are coherent SI (factor 1, offset 0).

/// Exponents of the base units, in the order of [`BASE_UNIT_NAMES`].
type Exponents = [i32; 8];

/// The attribute names of `<BaseUnit>` in the order of `Exponents`.
pub const BASE_UNIT_NAMES: [&str; 8] = ["kg", "m", "s", "A", "K", "mol", "cd", "rad"];

/// `(unit, exponents of kg, m, s, A, K, mol, cd, rad)`.
const UNITS: &[(&str, Exponents)] = &[
    ("1", [0, 0, 0, 0, 0, 0, 0, 0]),
    ("kg", [1, 0, 0, 0, 0, 0, 0, 0]),
    ("m", [0, 1, 0, 0, 0, 0, 0, 0]),
    ("s", [0, 0, 1, 0, 0, 0, 0, 0]),
    ("A", [0, 0, 0, 1, 0, 0, 0, 0]),
    ("K", [0, 0, 0, 0, 1, 0, 0, 0]),
    ("rad", [0, 0, 0, 0, 0, 0, 0, 1]),
    ("Hz", [0, 0, -1, 0, 0, 0, 0, 0]),
    ("m2", [0, 2, 0, 0, 0, 0, 0, 0]),
    ("m3", [0, 3, 0, 0, 0, 0, 0, 0]),
    ("m/s", [0, 1, -1, 0, 0, 0, 0, 0]),
    ("m/s2", [0, 1, -2, 0, 0, 0, 0, 0]),
    ("rad/s", [0, 0, -1, 0, 0, 0, 0, 1]),
    ("rad/s2", [0, 0, -2, 0, 0, 0, 0, 1]),
    ("kg/m3", [1, -3, 0, 0, 0, 0, 0, 0]),
    ("kg.m2", [1, 2, 0, 0, 0, 0, 0, 0]),
    ("kg.m/s", [1, 1, -1, 0, 0, 0, 0, 0]),
    ("N", [1, 1, -2, 0, 0, 0, 0, 0]),
    ("N/m", [1, 0, -2, 0, 0, 0, 0, 0]),
    ("N.s/m", [1, 0, -1, 0, 0, 0, 0, 0]),
    ("N.m", [1, 2, -2, 0, 0, 0, 0, 0]),
    ("N.m/rad", [1, 2, -2, 0, 0, 0, 0, -1]),
    ("N.m.s/rad", [1, 2, -1, 0, 0, 0, 0, -1]),
    ("Pa", [1, -1, -2, 0, 0, 0, 0, 0]),
    ("J", [1, 2, -2, 0, 0, 0, 0, 0]),
    ("W", [1, 2, -3, 0, 0, 0, 0, 0]),
    ("V", [1, 2, -3, -1, 0, 0, 0, 0]),
    ("V/m", [1, 1, -3, -1, 0, 0, 0, 0]),
    ("C", [0, 0, 1, 1, 0, 0, 0, 0]),
    ("C/m2", [0, -2, 1, 1, 0, 0, 0, 0]),
    ("F", [-1, -2, 4, 2, 0, 0, 0, 0]),
    ("F/m", [-1, -3, 4, 2, 0, 0, 0, 0]),
    ("ohm", [1, 2, -3, -2, 0, 0, 0, 0]),
    ("Ohm", [1, 2, -3, -2, 0, 0, 0, 0]),
    ("S", [-1, -2, 3, 2, 0, 0, 0, 0]),
    ("A/s", [0, 0, -1, 1, 0, 0, 0, 0]),
    ("V/s", [1, 2, -4, -1, 0, 0, 0, 0]),
];

/// The base-unit exponents of `unit`, or `None` if the unit is not in the table.
pub fn base_unit(unit: &str) -> Option<Exponents> {
    UNITS
        .iter()
        .find(|(name, _)| *name == unit)
        .map(|(_, e)| *e)
}

/// The unit of the table for the time derivative of a quantity in `unit` (the first one with
/// the same base units divided by a second), e.g. `C` gives `A`.
pub fn per_second(unit: &str) -> Option<&'static str> {
    let mut e = base_unit(unit)?;
    e[2] -= 1;
    UNITS.iter().find(|(_, x)| *x == e).map(|(name, _)| *name)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Exponents of the symbols unit strings are built from, derived by hand from the SI
    /// definitions independently of the table.
    fn symbol(sym: &str) -> Exponents {
        let si = |kg, m, s, a, rad| [kg, m, s, a, 0, 0, 0, rad];
        match sym {
            "1" => si(0, 0, 0, 0, 0),
            "kg" => si(1, 0, 0, 0, 0),
            "m" => si(0, 1, 0, 0, 0),
            "s" => si(0, 0, 1, 0, 0),
            "A" => si(0, 0, 0, 1, 0),
            "K" => [0, 0, 0, 0, 1, 0, 0, 0],
            "rad" => si(0, 0, 0, 0, 1),
            "Hz" => si(0, 0, -1, 0, 0),
            "N" => si(1, 1, -2, 0, 0),
            "Pa" => si(1, -1, -2, 0, 0),
            "J" => si(1, 2, -2, 0, 0),
            "W" => si(1, 2, -3, 0, 0),
            "C" => si(0, 0, 1, 1, 0),
            // V = W/A, F = C/V, ohm = V/A, S = A/V
            "V" => si(1, 2, -3, -1, 0),
            "F" => si(-1, -2, 4, 2, 0),
            "ohm" | "Ohm" => si(1, 2, -3, -2, 0),
            "S" => si(-1, -2, 3, 2, 0),
            other => panic!("unknown symbol {other:?}"),
        }
    }

    /// Parses the Modelica unit syntax used here: factors joined by `.`, at most one `/`,
    /// each factor a symbol with an optional integer exponent (`m2`, `s2`).
    fn parse(unit: &str) -> Exponents {
        let (num, den) = unit.split_once('/').unwrap_or((unit, ""));
        let mut total = [0; 8];
        for (part, sign) in [(num, 1), (den, -1)] {
            for factor in part.split('.').filter(|f| !f.is_empty()) {
                let split = factor
                    .find(|c: char| c.is_ascii_digit() || c == '-')
                    .filter(|&i| i > 0)
                    .unwrap_or(factor.len());
                let (sym, pow) = factor.split_at(split);
                let pow: i32 = if pow.is_empty() {
                    1
                } else {
                    pow.parse().unwrap()
                };
                for (t, s) in total.iter_mut().zip(symbol(sym)) {
                    *t += sign * pow * s;
                }
            }
        }
        total
    }

    #[test]
    fn every_table_entry_matches_its_name() {
        for (name, exps) in UNITS {
            assert_eq!(parse(name), *exps, "unit {name}");
        }
    }

    #[test]
    fn names_are_unique() {
        for (i, (a, _)) in UNITS.iter().enumerate() {
            assert!(UNITS[i + 1..].iter().all(|(b, _)| a != b), "{a} twice");
        }
    }

    #[test]
    fn lookup() {
        assert_eq!(base_unit("V"), Some([1, 2, -3, -1, 0, 0, 0, 0]));
        assert_eq!(base_unit("furlong"), None);
    }

    #[test]
    fn rates() {
        for (unit, rate) in [("rad", "rad/s"), ("m", "m/s"), ("C", "A"), ("kg.m/s", "N")] {
            assert_eq!(per_second(unit), Some(rate), "{unit}");
        }
        assert_eq!(per_second("furlong"), None);
        assert_eq!(per_second("F/m"), None);
    }
}
