//! [`export_fmi2!`](crate::export_fmi2): the 44 functions of `fmi2Functions.h` for one core,
//! each handing its arguments to the function of [`calls`](crate::fmi_common::calls) both
//! versions share, or of [`exports`](super::exports) where FMI 2.0 has its own.

/// Exports the 44 functions of `fmi2Functions.h` for the core type `$core` (an
/// [`FmuCore`](crate::fmi_common::model_api::FmuCore)). Invoke exactly once per shared
/// library, at item level of a module of its own (it imports the C types there):
/// `mod fmi2_functions { hasel_fmu::export_fmi2!(super::MyCore); }` (inside this crate:
/// `crate::export_fmi2!`).
#[macro_export]
macro_rules! export_fmi2 {
    ($core:ty) => {
        $crate::__fmi2_functions!([#[unsafe(no_mangle)]] $core);
    };
}

/// The functions of [`export_fmi2!`]; the bracketed attributes go on each function (tests
/// pass none, to get the C-ABI functions without exported symbol names).
#[doc(hidden)]
#[macro_export]
macro_rules! __fmi2_functions {
    ([$($attr:tt)*] $core:ty) => {
        use $crate::fmi2::exports as shell;
        use $crate::fmi2::Fmi2;
        use $crate::fmi2::instance::Instance;
        use $crate::fmi2::types::*;
        use $crate::fmi_common::calls as common;

        // Inquire platform and version number of the header files (section 2.1.4)

        $($attr)* #[allow(non_snake_case)]
        pub extern "C" fn fmi2GetTypesPlatform() -> *const ::std::ffi::c_char {
            shell::static_c_str(TYPES_PLATFORM)
        }

        $($attr)* #[allow(non_snake_case)]
        pub extern "C" fn fmi2GetVersion() -> *const ::std::ffi::c_char {
            shell::static_c_str(VERSION)
        }

        // Creation and destruction of instances, debug logging, and the calls without arguments
        // (sections 2.1.5, 2.1.6, 3.2.2)

        $crate::__fmi_lifecycle_functions!([$($attr)*] $core, Fmi2, fmi2Component, fmi2Status, fmi2Boolean, fmi2String,
            [fmi2SetDebugLogging, fmi2FreeInstance],
            [fmi2ExitInitializationMode: exit_initialization_mode, fmi2Terminate: terminate, fmi2Reset: reset,
             fmi2EnterEventMode: enter_event_mode]);

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2Instantiate(
            name: fmi2String,
            fmu_type: fmi2Type,
            guid: fmi2String,
            resources: fmi2String,
            functions: *const fmi2CallbackFunctions,
            _visible: fmi2Boolean, // no user interface to show (section 2.1.6)
            logging_on: fmi2Boolean,
        ) -> fmi2Component {
            unsafe {
                shell::instantiate::<$core>(name, fmu_type, guid, resources, functions, logging_on)
            }
        }

        // Initialization, termination and reset (section 2.1.6)

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SetupExperiment(
            c: fmi2Component,
            tol_defined: fmi2Boolean,
            tol: fmi2Real,
            start: fmi2Real,
            stop_defined: fmi2Boolean,
            stop: fmi2Real,
        ) -> fmi2Status {
            unsafe {
                shell::setup_experiment::<$core>(c, tol_defined, tol, start, stop_defined, stop)
            }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2EnterInitializationMode(c: fmi2Component) -> fmi2Status {
            unsafe { common::simple::<Fmi2, $core>(c, "fmi2EnterInitializationMode", Instance::enter_initialization_mode) }
        }

        // Getting and setting variable values (section 2.1.7); Real variables only

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetReal(
            c: fmi2Component,
            vr: *const fmi2ValueReference,
            nvr: usize,
            value: *mut fmi2Real,
        ) -> fmi2Status {
            unsafe { common::get_values::<Fmi2, $core>(c, (vr, nvr), (value, nvr)) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SetReal(
            c: fmi2Component,
            vr: *const fmi2ValueReference,
            nvr: usize,
            value: *const fmi2Real,
        ) -> fmi2Status {
            unsafe { common::set_values::<Fmi2, $core>(c, (vr, nvr), (value, nvr)) }
        }

        $crate::__fmi_no_variables_functions!([$($attr)*] $core, Fmi2, fmi2Component, fmi2Status, fmi2ValueReference,
            [(fmi2GetInteger, fmi2SetInteger, fmi2Integer), (fmi2GetBoolean, fmi2SetBoolean, fmi2Boolean),
             (fmi2GetString, fmi2SetString, fmi2String)]);

        // FMU states (section 2.1.8)

        $crate::__fmi_fmu_state_functions!([$($attr)*] $core, Fmi2, fmi2Component, fmi2Status, fmi2FMUstate, fmi2Byte,
            [fmi2GetFMUstate, fmi2SetFMUstate, fmi2FreeFMUstate, fmi2SerializedFMUstateSize, fmi2SerializeFMUstate,
             fmi2DeSerializeFMUstate]);

        // Directional derivatives (section 2.1.9)

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetDirectionalDerivative(
            c: fmi2Component,
            v_unknown_ref: *const fmi2ValueReference,
            n_unknown: usize,
            v_known_ref: *const fmi2ValueReference,
            n_known: usize,
            dv_known: *const fmi2Real,
            dv_unknown: *mut fmi2Real,
        ) -> fmi2Status {
            let arrays = common::DerivativeArrays {
                unknowns: (v_unknown_ref, n_unknown),
                knowns: (v_known_ref, n_known),
                seed: (dv_known, n_known),
                sensitivity: (dv_unknown, n_unknown),
            };
            let call = Instance::get_directional_derivative;
            unsafe { common::get_directional_derivative::<Fmi2, $core>(c, arrays, call) }
        }

        // Model Exchange (section 3.2)

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2NewDiscreteStates(
            c: fmi2Component,
            event_info: *mut fmi2EventInfo,
        ) -> fmi2Status {
            unsafe { shell::new_discrete_states::<$core>(c, event_info) }
        }

        $crate::__fmi_model_exchange_functions!([$($attr)*] $core, Fmi2, fmi2Component, fmi2Status, fmi2Boolean,
            [fmi2EnterContinuousTimeMode, fmi2CompletedIntegratorStep, fmi2SetTime, fmi2SetContinuousStates,
             fmi2GetEventIndicators],
            [(fmi2GetDerivatives, "derivatives", get_derivatives), (fmi2GetContinuousStates, "x", get_continuous_states),
             (fmi2GetNominalsOfContinuousStates, "x_nominal", get_nominals)]);

        // Co-Simulation (section 4.2)

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SetRealInputDerivatives(
            c: fmi2Component,
            _vr: *const fmi2ValueReference,
            _nvr: usize,
            _order: *const fmi2Integer,
            _value: *const fmi2Real,
        ) -> fmi2Status {
            let what = "canInterpolateInputs (input derivatives)";
            unsafe { common::not_offered::<Fmi2, $core>(c, "fmi2SetRealInputDerivatives", what) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetRealOutputDerivatives(
            c: fmi2Component,
            _vr: *const fmi2ValueReference,
            _nvr: usize,
            _order: *const fmi2Integer,
            _value: *mut fmi2Real,
        ) -> fmi2Status {
            let what = "maxOutputDerivativeOrder > 0 (output derivatives)";
            unsafe { common::not_offered::<Fmi2, $core>(c, "fmi2GetRealOutputDerivatives", what) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2DoStep(
            c: fmi2Component,
            tc: fmi2Real,
            h: fmi2Real,
            no_set_prior: fmi2Boolean,
        ) -> fmi2Status {
            unsafe { shell::do_step::<$core>(c, tc, h, no_set_prior) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2CancelStep(c: fmi2Component) -> fmi2Status {
            unsafe { common::simple::<Fmi2, $core>(c, "fmi2CancelStep", |inst| inst.cancel_step()) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetStatus(
            c: fmi2Component,
            kind: fmi2StatusKind,
            value: *mut fmi2Status,
        ) -> fmi2Status {
            unsafe { shell::get_valueless_status::<$core>(c, "fmi2GetStatus", kind, value.cast()) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetRealStatus(
            c: fmi2Component,
            kind: fmi2StatusKind,
            value: *mut fmi2Real,
        ) -> fmi2Status {
            unsafe { shell::get_real_status::<$core>(c, kind, value) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetIntegerStatus(
            c: fmi2Component,
            kind: fmi2StatusKind,
            value: *mut fmi2Integer,
        ) -> fmi2Status {
            unsafe {
                shell::get_valueless_status::<$core>(c, "fmi2GetIntegerStatus", kind, value.cast())
            }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetBooleanStatus(
            c: fmi2Component,
            kind: fmi2StatusKind,
            value: *mut fmi2Boolean,
        ) -> fmi2Status {
            unsafe { shell::get_boolean_status::<$core>(c, kind, value) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetStringStatus(
            c: fmi2Component,
            kind: fmi2StatusKind,
            value: *mut fmi2String,
        ) -> fmi2Status {
            unsafe {
                shell::get_valueless_status::<$core>(c, "fmi2GetStringStatus", kind, value.cast())
            }
        }
    };
}
