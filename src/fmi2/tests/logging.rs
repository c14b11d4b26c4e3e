//! The logger rules: "%s" format, categories, debug filtering.

use std::ptr::null;

use super::*;

#[test]
fn user_text_with_percent_is_delivered_literally() {
    let guid = "{%s%n%d}";
    let (c, log) = instantiate_raw("lag %s%n", FMI2_CO_SIMULATION, guid, None, false);
    assert!(c.is_null());
    log.assert_error(&["GUID {%s%n%d} given by the importer"]);
    assert_eq!(log.records()[0].instance, "lag %s%n");
    assert_eq!(log.records()[0].category, "logStatusError");
    let fmu = Fmu::new();
    let category = c"%s%n";
    assert_eq!(
        unsafe { toy::fmi2SetDebugLogging(fmu.c, FMI2_TRUE, 1, &category.as_ptr()) },
        Fmi2Status::Error
    );
    fmu.log.assert_error(&["unknown log category \"%s%n\""]);
}

#[test]
fn debug_messages_only_when_debug_logging_is_on() {
    let fmu = Fmu::running(0.0);
    assert_eq!(fmu.step(0.0, 0.1), Fmi2Status::Ok);
    assert!(
        fmu.log.records().is_empty(),
        "loggingOn = false: {:?}",
        fmu.log.records()
    );
    assert_eq!(fmu.step(0.0, 0.1), Fmi2Status::Error);
    assert_eq!(fmu.log.records().len(), 1, "errors are always logged");

    fmu.log.clear();
    assert_eq!(
        unsafe { toy::fmi2SetDebugLogging(fmu.c, FMI2_TRUE, 0, null()) },
        Fmi2Status::Ok
    );
    assert_eq!(fmu.set(U, 0.5), Fmi2Status::Ok);
    assert_eq!(fmu.step(0.1, 0.1), Fmi2Status::Ok);
    let debug = fmu.log.text(Fmi2Status::Ok);
    assert!(
        debug.contains("fmi2SetReal: u = 0.5")
            && debug.contains("fmi2DoStep(currentCommunicationPoint=0.1"),
        "{debug}"
    );
    assert!(
        fmu.log
            .records()
            .iter()
            .all(|r| r.category == "logCalls" && r.instance == "lag")
    );

    fmu.log.clear();
    let only_errors = c"logStatusError";
    assert_eq!(
        unsafe { toy::fmi2SetDebugLogging(fmu.c, FMI2_TRUE, 1, &only_errors.as_ptr()) },
        Fmi2Status::Ok
    );
    assert_eq!(fmu.step(0.2, 0.1), Fmi2Status::Ok);
    assert!(fmu.log.records().is_empty(), "logCalls not enabled");
    let model = c"logModel";
    assert_eq!(
        unsafe { toy::fmi2SetDebugLogging(fmu.c, FMI2_TRUE, 1, &model.as_ptr()) },
        Fmi2Status::Ok,
        "model categories are known"
    );
    assert_eq!(
        unsafe { toy::fmi2SetDebugLogging(fmu.c, FMI2_TRUE, 1, null()) },
        Fmi2Status::Error
    );
    fmu.log.assert_error(&["argument categories is NULL"]);

    fmu.log.clear();
    assert_eq!(
        unsafe { toy::fmi2SetDebugLogging(fmu.c, FMI2_FALSE, 0, null()) },
        Fmi2Status::Ok
    );
    assert_eq!(fmu.step(0.3, 0.1), Fmi2Status::Ok);
    assert!(fmu.log.records().is_empty());
}

#[test]
fn logging_on_at_instantiation_traces_calls() {
    let (c, log) = instantiate_raw("traced", FMI2_CO_SIMULATION, &toy_guid(), None, true);
    assert!(!c.is_null());
    unsafe { toy::fmi2FreeInstance(c) };
    assert!(
        log.text(Fmi2Status::Ok).contains("fmi2Instantiate"),
        "{:?}",
        log.records()
    );
}
