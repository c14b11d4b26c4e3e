//! modelDescription.xml: well-formed, complete, GUID behaviour; the exported signatures.

use quick_xml::Reader;
use quick_xml::events::Event;

use super::super::model_description::model_description_xml;
use super::*;

/// (element name, attributes) of every start or empty tag, checking well-formedness.
fn elements(xml: &str) -> Vec<(String, Vec<(String, String)>)> {
    let mut reader = Reader::from_str(xml);
    let mut out = Vec::new();
    loop {
        match reader.read_event().expect("well-formed XML") {
            Event::Eof => break,
            Event::Start(e) | Event::Empty(e) => {
                let attrs = e
                    .attributes()
                    .map(|a| {
                        let a = a.expect("well-formed attribute");
                        (
                            a.key.as_ref().to_string(),
                            a.normalized_value(quick_xml::XmlVersion::Implicit1_0)
                                .unwrap()
                                .into_owned(),
                        )
                    })
                    .collect();
                out.push((e.name().as_ref().to_string(), attrs));
            }
            _ => {}
        }
    }
    out
}

fn attr<'a>(attrs: &'a [(String, String)], key: &str) -> Option<&'a str> {
    attrs
        .iter()
        .find(|(k, _)| k == key)
        .map(|(_, v)| v.as_str())
}

fn toy_xml() -> String {
    model_description_xml(
        &LagCore::model_info(),
        &LagCore::instantiate(InstanceKind::CoSimulation, None)
            .unwrap()
            .variables(),
    )
    .unwrap()
}

#[test]
fn xml_is_well_formed_and_complete() {
    let xml = toy_xml();
    let els = elements(&xml);
    let (root, root_attrs) = &els[0];
    assert_eq!(root, "fmiModelDescription");
    assert_eq!(attr(root_attrs, "fmiVersion"), Some("2.0"));
    assert_eq!(attr(root_attrs, "guid"), Some(toy_guid().as_str()));
    assert_eq!(
        attr(root_attrs, "description"),
        Some("first-order lag <test> & \"quotes\""),
        "escaped and read back"
    );
    assert_eq!(attr(root_attrs, "numberOfEventIndicators"), Some("0"));
    let find = |name: &str| {
        els.iter()
            .filter(|(n, _)| n == name)
            .map(|(_, a)| a.clone())
            .collect::<Vec<_>>()
    };
    let cs = &find("CoSimulation")[0];
    assert_eq!(attr(cs, "modelIdentifier"), Some("Lag"));
    assert_eq!(attr(cs, "canGetAndSetFMUstate"), Some("true"));
    assert_eq!(attr(cs, "canRunAsynchronuously"), Some("false"));
    let vars = find("ScalarVariable");
    assert_eq!(vars.len(), 8);
    assert_eq!(attr(&vars[0], "initial"), Some("exact"));
    assert_eq!(attr(&vars[4], "initial"), None, "inputs have no initial");
    assert_eq!(attr(&vars[5], "initial"), Some("calculated"));
    let reals = find("Real");
    assert_eq!(attr(&reals[0], "start"), Some("1.0"));
    assert_eq!(attr(&reals[5], "start"), None);
    let units: Vec<String> = find("Unit")
        .iter()
        .map(|a| attr(a, "name").unwrap().to_string())
        .collect();
    assert_eq!(units, ["1", "Hz", "s"]);
    let base = find("BaseUnit");
    assert_eq!(attr(&base[1], "s"), Some("-1"));
    let categories: Vec<String> = find("Category")
        .iter()
        .map(|a| attr(a, "name").unwrap().to_string())
        .collect();
    assert!(
        categories.contains(&"logCalls".to_string())
            && categories.contains(&"logModel".to_string())
    );
    assert_eq!(
        attr(&find("DefaultExperiment")[0], "stepSize"),
        Some("0.01")
    );
    // ModelStructure: Outputs then InitialUnknowns
    let unknowns = find("Unknown");
    assert_eq!(unknowns.len(), 3);
    assert_eq!(
        (
            attr(&unknowns[0], "index"),
            attr(&unknowns[0], "dependencies")
        ),
        (Some("6"), Some(""))
    );
    assert_eq!(
        (
            attr(&unknowns[1], "index"),
            attr(&unknowns[1], "dependencies")
        ),
        (Some("6"), None)
    );
    assert_eq!(attr(&unknowns[2], "index"), Some("7"));
}

#[test]
fn guid_is_stable_and_follows_every_change() {
    let info = LagCore::model_info();
    let vars = LagCore::instantiate(InstanceKind::CoSimulation, None)
        .unwrap()
        .variables();
    let guid = guid_for(&info, &vars).unwrap();
    assert_eq!(guid, guid_for(&info, &vars).unwrap());
    assert_eq!(guid.len(), 38);
    assert!(guid.starts_with('{') && guid.ends_with('}') && guid.as_bytes()[15] == b'8');
    let mut changed = vars.clone();
    changed[1].start = Some(1e-300);
    assert_ne!(guid_for(&info, &changed).unwrap(), guid);
    let mut changed = vars.clone();
    changed[4].description.push('.');
    assert_ne!(guid_for(&info, &changed).unwrap(), guid);
    let mut info2 = info.clone();
    info2.default_experiment.stop_time = 11.0;
    assert_ne!(guid_for(&info2, &vars).unwrap(), guid);
}

#[test]
fn invalid_tables_and_infos_are_rejected() {
    let info = LagCore::model_info();
    let mut vars = LagCore::instantiate(InstanceKind::CoSimulation, None)
        .unwrap()
        .variables();
    vars[1].value_reference = vars[0].value_reference;
    assert!(
        model_description_xml(&info, &vars)
            .unwrap_err()
            .contains("used twice")
    );
    let vars = LagCore::instantiate(InstanceKind::CoSimulation, None)
        .unwrap()
        .variables();
    let mut bad = info.clone();
    bad.default_experiment.tolerance = f64::INFINITY;
    assert!(model_description_xml(&bad, &vars).is_err());
    let mut bad = info;
    bad.model_identifier = "my model".into();
    assert!(model_description_xml(&bad, &vars).is_err());
}

#[test]
fn floats_round_trip_exactly() {
    let info = LagCore::model_info();
    let mut vars = LagCore::instantiate(InstanceKind::CoSimulation, None)
        .unwrap()
        .variables();
    let values = [
        0.1,
        1.0 / 3.0,
        1e-300,
        -2.5e17,
        f64::MIN_POSITIVE,
        5e-324,
        f64::MAX,
    ];
    for (v, x) in vars.iter_mut().zip(values.iter().take(4)) {
        v.start = Some(*x);
    }
    let xml = model_description_xml(&info, &vars).unwrap();
    let starts: Vec<f64> = elements(&xml)
        .iter()
        .filter(|(n, _)| n == "Real")
        .filter_map(|(_, a)| attr(a, "start").map(|s| s.parse().unwrap()))
        .collect();
    assert_eq!(&starts[..4], &values[..4]);
    for x in values {
        assert_eq!(
            format!("{x:?}").parse::<f64>().unwrap().to_bits(),
            x.to_bits()
        );
    }
}

/// The 44 functions of fmi2Functions.h with the signatures of fmi2FunctionTypes.h.
#[test]
fn all_44_functions_have_the_header_signatures() {
    use std::ffi::c_char;
    type C = fmi2Component;
    type S = fmi2Status;
    type Vr = *const fmi2ValueReference;
    let common: [(&str, usize); 25] = [
        (
            "fmi2GetTypesPlatform",
            toy::fmi2GetTypesPlatform as extern "C" fn() -> *const c_char as usize,
        ),
        (
            "fmi2GetVersion",
            toy::fmi2GetVersion as extern "C" fn() -> *const c_char as usize,
        ),
        (
            "fmi2SetDebugLogging",
            toy::fmi2SetDebugLogging
                as unsafe extern "C" fn(C, fmi2Boolean, usize, *const fmi2String) -> S
                as usize,
        ),
        (
            "fmi2Instantiate",
            toy::fmi2Instantiate
                as unsafe extern "C" fn(
                    fmi2String,
                    fmi2Type,
                    fmi2String,
                    fmi2String,
                    *const fmi2CallbackFunctions,
                    fmi2Boolean,
                    fmi2Boolean,
                ) -> C as usize,
        ),
        (
            "fmi2FreeInstance",
            toy::fmi2FreeInstance as unsafe extern "C" fn(C) as usize,
        ),
        (
            "fmi2SetupExperiment",
            toy::fmi2SetupExperiment
                as unsafe extern "C" fn(C, fmi2Boolean, f64, f64, fmi2Boolean, f64) -> S
                as usize,
        ),
        (
            "fmi2EnterInitializationMode",
            toy::fmi2EnterInitializationMode as unsafe extern "C" fn(C) -> S as usize,
        ),
        (
            "fmi2ExitInitializationMode",
            toy::fmi2ExitInitializationMode as unsafe extern "C" fn(C) -> S as usize,
        ),
        (
            "fmi2Terminate",
            toy::fmi2Terminate as unsafe extern "C" fn(C) -> S as usize,
        ),
        (
            "fmi2Reset",
            toy::fmi2Reset as unsafe extern "C" fn(C) -> S as usize,
        ),
        (
            "fmi2GetReal",
            toy::fmi2GetReal as unsafe extern "C" fn(C, Vr, usize, *mut f64) -> S as usize,
        ),
        (
            "fmi2GetInteger",
            toy::fmi2GetInteger as unsafe extern "C" fn(C, Vr, usize, *mut fmi2Integer) -> S
                as usize,
        ),
        (
            "fmi2GetBoolean",
            toy::fmi2GetBoolean as unsafe extern "C" fn(C, Vr, usize, *mut fmi2Boolean) -> S
                as usize,
        ),
        (
            "fmi2GetString",
            toy::fmi2GetString as unsafe extern "C" fn(C, Vr, usize, *mut fmi2String) -> S as usize,
        ),
        (
            "fmi2SetReal",
            toy::fmi2SetReal as unsafe extern "C" fn(C, Vr, usize, *const f64) -> S as usize,
        ),
        (
            "fmi2SetInteger",
            toy::fmi2SetInteger as unsafe extern "C" fn(C, Vr, usize, *const fmi2Integer) -> S
                as usize,
        ),
        (
            "fmi2SetBoolean",
            toy::fmi2SetBoolean as unsafe extern "C" fn(C, Vr, usize, *const fmi2Boolean) -> S
                as usize,
        ),
        (
            "fmi2SetString",
            toy::fmi2SetString as unsafe extern "C" fn(C, Vr, usize, *const fmi2String) -> S
                as usize,
        ),
        (
            "fmi2GetFMUstate",
            toy::fmi2GetFMUstate as unsafe extern "C" fn(C, *mut fmi2FMUstate) -> S as usize,
        ),
        (
            "fmi2SetFMUstate",
            toy::fmi2SetFMUstate as unsafe extern "C" fn(C, fmi2FMUstate) -> S as usize,
        ),
        (
            "fmi2FreeFMUstate",
            toy::fmi2FreeFMUstate as unsafe extern "C" fn(C, *mut fmi2FMUstate) -> S as usize,
        ),
        (
            "fmi2SerializedFMUstateSize",
            toy::fmi2SerializedFMUstateSize
                as unsafe extern "C" fn(C, fmi2FMUstate, *mut usize) -> S as usize,
        ),
        (
            "fmi2SerializeFMUstate",
            toy::fmi2SerializeFMUstate
                as unsafe extern "C" fn(C, fmi2FMUstate, *mut fmi2Byte, usize) -> S
                as usize,
        ),
        (
            "fmi2DeSerializeFMUstate",
            toy::fmi2DeSerializeFMUstate
                as unsafe extern "C" fn(C, *const fmi2Byte, usize, *mut fmi2FMUstate) -> S
                as usize,
        ),
        (
            "fmi2GetDirectionalDerivative",
            toy::fmi2GetDirectionalDerivative
                as unsafe extern "C" fn(C, Vr, usize, Vr, usize, *const f64, *mut f64) -> S
                as usize,
        ),
    ];
    let model_exchange: [(&str, usize); 10] = [
        (
            "fmi2EnterEventMode",
            toy::fmi2EnterEventMode as unsafe extern "C" fn(C) -> S as usize,
        ),
        (
            "fmi2NewDiscreteStates",
            toy::fmi2NewDiscreteStates as unsafe extern "C" fn(C, *mut fmi2EventInfo) -> S as usize,
        ),
        (
            "fmi2EnterContinuousTimeMode",
            toy::fmi2EnterContinuousTimeMode as unsafe extern "C" fn(C) -> S as usize,
        ),
        (
            "fmi2CompletedIntegratorStep",
            toy::fmi2CompletedIntegratorStep
                as unsafe extern "C" fn(C, fmi2Boolean, *mut fmi2Boolean, *mut fmi2Boolean) -> S
                as usize,
        ),
        (
            "fmi2SetTime",
            toy::fmi2SetTime as unsafe extern "C" fn(C, f64) -> S as usize,
        ),
        (
            "fmi2SetContinuousStates",
            toy::fmi2SetContinuousStates as unsafe extern "C" fn(C, *const f64, usize) -> S
                as usize,
        ),
        (
            "fmi2GetDerivatives",
            toy::fmi2GetDerivatives as unsafe extern "C" fn(C, *mut f64, usize) -> S as usize,
        ),
        (
            "fmi2GetEventIndicators",
            toy::fmi2GetEventIndicators as unsafe extern "C" fn(C, *mut f64, usize) -> S as usize,
        ),
        (
            "fmi2GetContinuousStates",
            toy::fmi2GetContinuousStates as unsafe extern "C" fn(C, *mut f64, usize) -> S as usize,
        ),
        (
            "fmi2GetNominalsOfContinuousStates",
            toy::fmi2GetNominalsOfContinuousStates as unsafe extern "C" fn(C, *mut f64, usize) -> S
                as usize,
        ),
    ];
    let co_simulation: [(&str, usize); 9] = [
        (
            "fmi2SetRealInputDerivatives",
            toy::fmi2SetRealInputDerivatives
                as unsafe extern "C" fn(C, Vr, usize, *const fmi2Integer, *const f64) -> S
                as usize,
        ),
        (
            "fmi2GetRealOutputDerivatives",
            toy::fmi2GetRealOutputDerivatives
                as unsafe extern "C" fn(C, Vr, usize, *const fmi2Integer, *mut f64) -> S
                as usize,
        ),
        (
            "fmi2DoStep",
            toy::fmi2DoStep as unsafe extern "C" fn(C, f64, f64, fmi2Boolean) -> S as usize,
        ),
        (
            "fmi2CancelStep",
            toy::fmi2CancelStep as unsafe extern "C" fn(C) -> S as usize,
        ),
        (
            "fmi2GetStatus",
            toy::fmi2GetStatus as unsafe extern "C" fn(C, fmi2StatusKind, *mut fmi2Status) -> S
                as usize,
        ),
        (
            "fmi2GetRealStatus",
            toy::fmi2GetRealStatus as unsafe extern "C" fn(C, fmi2StatusKind, *mut f64) -> S
                as usize,
        ),
        (
            "fmi2GetIntegerStatus",
            toy::fmi2GetIntegerStatus
                as unsafe extern "C" fn(C, fmi2StatusKind, *mut fmi2Integer) -> S
                as usize,
        ),
        (
            "fmi2GetBooleanStatus",
            toy::fmi2GetBooleanStatus
                as unsafe extern "C" fn(C, fmi2StatusKind, *mut fmi2Boolean) -> S
                as usize,
        ),
        (
            "fmi2GetStringStatus",
            toy::fmi2GetStringStatus
                as unsafe extern "C" fn(C, fmi2StatusKind, *mut fmi2String) -> S
                as usize,
        ),
    ];
    let all: Vec<_> = common
        .iter()
        .chain(&model_exchange)
        .chain(&co_simulation)
        .collect();
    assert_eq!(all.len(), 44);
    let names: std::collections::HashSet<_> = all.iter().map(|(n, _)| n).collect();
    assert_eq!(names.len(), 44);
    assert!(all.iter().all(|(_, f)| *f != 0));
}
