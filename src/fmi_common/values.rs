//! Getting and setting the Real (FMI 3.0: Float64) variables of a core by value reference, for
//! both shells (FMI 2.0 section 2.1.7, FMI 3.0 section 2.3.3): the references looked up in the
//! variable table, the state's rule of what may be set ([`SetRule`]), NaN refused, the core's
//! messages named with the variable. The shells check the state and the arguments before and
//! log the message of an `Err` under their function's name.

use super::model_api::FmuCore;
use super::state_machine::{SetRule, settable};
use super::variables::{Causality, Variable};

/// The variable with value reference `vr` in a table sorted by value reference.
pub fn find(variables: &[Variable], vr: u32) -> Option<&Variable> {
    // the tables number their variables by position: the reference is usually the index (a
    // co-simulation step looks up nine references: a search each was a tenth of its cost)
    if let Some(v) = variables.get(vr as usize)
        && v.value_reference == vr
    {
        return Some(v);
    }
    let i = variables
        .binary_search_by_key(&vr, |v| v.value_reference)
        .ok()?;
    Some(&variables[i])
}

fn unknown(vr: u32) -> String {
    format!("unknown value reference {vr}")
}

/// The values of `vrs` into `values` (as many); the independent variable is the core's time.
pub fn get<M: FmuCore>(
    core: &mut M,
    variables: &[Variable],
    vrs: &[u32],
    values: &mut [f64],
) -> Result<(), String> {
    for (&vr, value) in vrs.iter().zip(values.iter_mut()) {
        let v = find(variables, vr).ok_or_else(|| unknown(vr))?;
        let x = if v.causality == Causality::Independent {
            Ok(core.time())
        } else {
            core.get_real(vr)
        };
        *value = x.map_err(|msg| format!("{} (value reference {vr}): {msg}", v.name))?;
    }
    Ok(())
}

/// Sets `values` to `vrs` in a state of `rule` (named `state` in messages). All references are
/// checked before any value is set; values are then set in order (each traced), and a value the
/// core rejects stops there.
pub fn set<M: FmuCore>(
    core: &mut M,
    variables: &[Variable],
    (rule, state): (SetRule, &str),
    (vrs, values): (&[u32], &[f64]),
    trace: impl Fn(&str, f64),
) -> Result<(), String> {
    for &vr in vrs {
        let v = find(variables, vr).ok_or_else(|| unknown(vr))?;
        if !settable(rule, v) {
            let initial = v.effective_initial().map_or("none", |i| i.as_str());
            return Err(format!(
                "{} (value reference {vr}, causality {}, variability {}, initial {initial}) cannot be set in state {state}",
                v.name,
                v.causality.as_str(),
                v.variability.as_str(),
            ));
        }
    }
    for (&vr, &value) in vrs.iter().zip(values) {
        let name = find(variables, vr).map_or("", |v| v.name.as_str());
        trace(name, value);
        if value.is_nan() {
            return Err(format!("{name} (value reference {vr}): value is NaN"));
        }
        core.set_real(vr, value)
            .map_err(|msg| format!("{name} (value reference {vr}) = {value:?} rejected: {msg}"))?;
    }
    Ok(())
}

/// The message of a getter or setter of a type the table has no variables of (`type_name`,
/// for the first of `vrs`); `None` when `vrs` is empty.
pub fn no_variables_of_type(
    variables: &[Variable],
    type_name: &str,
    real_type: &str,
    vrs: &[u32],
) -> Option<String> {
    let vr = *vrs.first()?;
    let what = match find(variables, vr) {
        Some(v) if !real_type.is_empty() => {
            format!("value reference {vr} is {}, a {real_type}", v.name)
        }
        _ => unknown(vr),
    };
    Some(format!("{what}: this FMU has no {type_name} variables"))
}
