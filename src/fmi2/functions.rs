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

        // Creation and destruction of instances, debug logging (sections 2.1.5, 2.1.6)

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SetDebugLogging(
            c: fmi2Component,
            logging_on: fmi2Boolean,
            n_categories: usize,
            categories: *const fmi2String,
        ) -> fmi2Status {
            unsafe { common::set_debug_logging::<Fmi2, $core>(c, logging_on != FMI2_FALSE, n_categories, categories) }
        }

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

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2FreeInstance(c: fmi2Component) {
            unsafe { common::free_instance::<Fmi2, $core>(c) }
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

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2ExitInitializationMode(c: fmi2Component) -> fmi2Status {
            unsafe { common::simple::<Fmi2, $core>(c, "fmi2ExitInitializationMode", Instance::exit_initialization_mode) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2Terminate(c: fmi2Component) -> fmi2Status {
            unsafe { common::simple::<Fmi2, $core>(c, "fmi2Terminate", Instance::terminate) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2Reset(c: fmi2Component) -> fmi2Status {
            unsafe { common::simple::<Fmi2, $core>(c, "fmi2Reset", Instance::reset) }
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
        pub unsafe extern "C" fn fmi2GetInteger(
            c: fmi2Component,
            vr: *const fmi2ValueReference,
            nvr: usize,
            value: *mut fmi2Integer,
        ) -> fmi2Status {
            unsafe { common::no_variables::<Fmi2, $core>(c, "fmi2GetInteger", (vr, nvr), value.cast()) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetBoolean(
            c: fmi2Component,
            vr: *const fmi2ValueReference,
            nvr: usize,
            value: *mut fmi2Boolean,
        ) -> fmi2Status {
            unsafe { common::no_variables::<Fmi2, $core>(c, "fmi2GetBoolean", (vr, nvr), value.cast()) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetString(
            c: fmi2Component,
            vr: *const fmi2ValueReference,
            nvr: usize,
            value: *mut fmi2String,
        ) -> fmi2Status {
            unsafe { common::no_variables::<Fmi2, $core>(c, "fmi2GetString", (vr, nvr), value.cast()) }
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

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SetInteger(
            c: fmi2Component,
            vr: *const fmi2ValueReference,
            nvr: usize,
            value: *const fmi2Integer,
        ) -> fmi2Status {
            unsafe { common::no_variables::<Fmi2, $core>(c, "fmi2SetInteger", (vr, nvr), value.cast()) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SetBoolean(
            c: fmi2Component,
            vr: *const fmi2ValueReference,
            nvr: usize,
            value: *const fmi2Boolean,
        ) -> fmi2Status {
            unsafe { common::no_variables::<Fmi2, $core>(c, "fmi2SetBoolean", (vr, nvr), value.cast()) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SetString(
            c: fmi2Component,
            vr: *const fmi2ValueReference,
            nvr: usize,
            value: *const fmi2String,
        ) -> fmi2Status {
            unsafe { common::no_variables::<Fmi2, $core>(c, "fmi2SetString", (vr, nvr), value.cast()) }
        }

        // FMU states (section 2.1.8)

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetFMUstate(
            c: fmi2Component,
            state: *mut fmi2FMUstate,
        ) -> fmi2Status {
            unsafe { common::get_fmu_state::<Fmi2, $core>(c, "fmi2GetFMUstate", state) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SetFMUstate(
            c: fmi2Component,
            state: fmi2FMUstate,
        ) -> fmi2Status {
            unsafe { common::set_fmu_state::<Fmi2, $core>(c, "fmi2SetFMUstate", state) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2FreeFMUstate(
            c: fmi2Component,
            state: *mut fmi2FMUstate,
        ) -> fmi2Status {
            unsafe { common::free_fmu_state::<Fmi2, $core>(c, "fmi2FreeFMUstate", state) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SerializedFMUstateSize(
            c: fmi2Component,
            state: fmi2FMUstate,
            size: *mut usize,
        ) -> fmi2Status {
            unsafe { common::serialized_fmu_state_size::<Fmi2, $core>(c, "fmi2SerializedFMUstateSize", state, size) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SerializeFMUstate(
            c: fmi2Component,
            state: fmi2FMUstate,
            bytes: *mut fmi2Byte,
            size: usize,
        ) -> fmi2Status {
            unsafe { common::serialize_fmu_state::<Fmi2, $core>(c, "fmi2SerializeFMUstate", state, bytes.cast(), size) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2DeSerializeFMUstate(
            c: fmi2Component,
            bytes: *const fmi2Byte,
            size: usize,
            state: *mut fmi2FMUstate,
        ) -> fmi2Status {
            unsafe { common::deserialize_fmu_state::<Fmi2, $core>(c, "fmi2DeSerializeFMUstate", bytes.cast(), size, state) }
        }

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
        pub unsafe extern "C" fn fmi2EnterEventMode(c: fmi2Component) -> fmi2Status {
            unsafe { common::simple::<Fmi2, $core>(c, "fmi2EnterEventMode", Instance::enter_event_mode) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2NewDiscreteStates(
            c: fmi2Component,
            event_info: *mut fmi2EventInfo,
        ) -> fmi2Status {
            unsafe { shell::new_discrete_states::<$core>(c, event_info) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2EnterContinuousTimeMode(c: fmi2Component) -> fmi2Status {
            unsafe { common::simple::<Fmi2, $core>(c, "fmi2EnterContinuousTimeMode", Instance::enter_continuous_time_mode) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2CompletedIntegratorStep(
            c: fmi2Component,
            _no_set_fmu_state_prior_to_current_point: fmi2Boolean,
            enter_event_mode: *mut fmi2Boolean,
            terminate_simulation: *mut fmi2Boolean,
        ) -> fmi2Status {
            unsafe { common::completed_integrator_step::<Fmi2, $core>(c, enter_event_mode, terminate_simulation) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SetTime(c: fmi2Component, time: fmi2Real) -> fmi2Status {
            unsafe { common::set_time::<Fmi2, $core>(c, time) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SetContinuousStates(
            c: fmi2Component,
            x: *const fmi2Real,
            nx: usize,
        ) -> fmi2Status {
            unsafe { common::set_continuous_states::<Fmi2, $core>(c, (x, nx), Instance::set_continuous_states) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetDerivatives(
            c: fmi2Component,
            derivatives: *mut fmi2Real,
            nx: usize,
        ) -> fmi2Status {
            let names = ("fmi2GetDerivatives", "derivatives");
            unsafe { common::get_state_vector::<Fmi2, $core>(c, names, (derivatives, nx), Instance::get_derivatives) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetEventIndicators(
            c: fmi2Component,
            event_indicators: *mut fmi2Real,
            ni: usize,
        ) -> fmi2Status {
            unsafe { common::get_event_indicators::<Fmi2, $core>(c, (event_indicators, ni)) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetContinuousStates(
            c: fmi2Component,
            x: *mut fmi2Real,
            nx: usize,
        ) -> fmi2Status {
            let names = ("fmi2GetContinuousStates", "x");
            unsafe { common::get_state_vector::<Fmi2, $core>(c, names, (x, nx), Instance::get_continuous_states) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetNominalsOfContinuousStates(
            c: fmi2Component,
            x_nominal: *mut fmi2Real,
            nx: usize,
        ) -> fmi2Status {
            let names = ("fmi2GetNominalsOfContinuousStates", "x_nominal");
            unsafe { common::get_state_vector::<Fmi2, $core>(c, names, (x_nominal, nx), Instance::get_nominals) }
        }

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
