//! Pieces of `modelDescription.xml` that FMI 2.0 and 3.0 write alike: numbers as `xs:double`
//! and the `<UnitDefinitions>` of the units a variable table uses (FMI 2.0 section 2.2.2,
//! FMI 3.0 section 2.4.3: the same `<Unit><BaseUnit/></Unit>` elements).

use std::collections::BTreeSet;
use std::io;

use quick_xml::Writer;

use super::units::{self, BASE_UNIT_NAMES};
use super::variables::Variable;

/// A double as `xs:double`: the shortest form that reads back to the same bits, infinities
/// as `INF` / `-INF`.
pub fn xs_double(x: f64) -> String {
    if x.is_infinite() {
        return if x > 0.0 { "INF" } else { "-INF" }.into();
    }
    format!("{x:?}")
}

/// `<UnitDefinitions>`: every unit of `vars`, with its SI base-unit exponents; nothing when no
/// variable has a unit. The table must have passed `check_variable_table` (known units only).
pub fn write_unit_definitions(w: &mut Writer<Vec<u8>>, vars: &[Variable]) -> io::Result<()> {
    let used: BTreeSet<&str> = vars.iter().filter_map(|v| v.unit.as_deref()).collect();
    if used.is_empty() {
        return Ok(());
    }
    w.create_element("UnitDefinitions")
        .write_inner_content(|w| {
            for unit in used {
                let exponents = units::base_unit(unit).unwrap_or_default();
                let base: Vec<(&str, String)> = BASE_UNIT_NAMES
                    .iter()
                    .zip(exponents)
                    .filter(|(_, e)| *e != 0)
                    .map(|(name, e)| (*name, e.to_string()))
                    .collect();
                w.create_element("Unit")
                    .with_attribute(("name", unit))
                    .write_inner_content(|w| {
                        w.create_element("BaseUnit")
                            .with_attributes(base.iter().map(|(n, e)| (*n, e.as_str())))
                            .write_empty()
                            .map(drop)
                    })?;
            }
            Ok(())
        })
        .map(drop)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn doubles_read_back_to_the_same_bits() {
        for x in [
            0.0,
            -0.0,
            1e-3,
            0.1 + 0.2,
            8.854187817e-12,
            f64::MAX,
            f64::MIN_POSITIVE,
        ] {
            assert_eq!(xs_double(x).parse::<f64>().unwrap().to_bits(), x.to_bits());
        }
        assert_eq!(xs_double(f64::INFINITY), "INF");
        assert_eq!(xs_double(f64::NEG_INFINITY), "-INF");
    }
}
