//! [`export_fmi3!`](crate::export_fmi3): the functions of `fmi3Functions.h` for one core,
//! each handing its arguments to the function of [`calls`](crate::fmi_common::calls) both
//! versions share, or of [`exports`](super::exports) where FMI 3.0 has its own.

/// Exports the functions of `fmi3Functions.h` for the core type `$core` (an
/// [`FmuCore`](crate::fmi_common::model_api::FmuCore)). Invoke exactly once per shared
/// library, at item level of a module of its own (it imports the C types there), and not in
/// the same library as [`export_fmi2!`](crate::export_fmi2): `mod fmi3_functions {
/// hasel_fmu::export_fmi3!(super::MyCore); }` (inside this crate: `crate::export_fmi3!`).
#[macro_export]
macro_rules! export_fmi3 {
    ($core:ty) => {
        $crate::__fmi3_functions!([#[unsafe(no_mangle)]] $core);
    };
}

/// The functions of [`export_fmi3!`]; the bracketed attributes go on each function (tests
/// pass none, to get the C-ABI functions without exported symbol names).
#[doc(hidden)]
#[macro_export]
macro_rules! __fmi3_functions {
    ([$($attr:tt)*] $core:ty) => {
        use $crate::fmi3::exports as shell;
        use $crate::fmi3::Fmi3;
        use $crate::fmi3::instance::Instance;
        use $crate::fmi_common::calls as common;
        use $crate::fmi_common::model_api::FmuCore as _;
        use $crate::fmi3::types::*;

        // Inquire version number and set debug logging (section 2.3.1)

        $($attr)* #[allow(non_snake_case)]
        pub extern "C" fn fmi3GetVersion() -> *const ::std::ffi::c_char {
            shell::version()
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi3SetDebugLogging(
            c: fmi3Instance,
            logging_on: fmi3Boolean,
            n_categories: usize,
            categories: *const fmi3String,
        ) -> fmi3Status {
            unsafe { common::set_debug_logging::<Fmi3, $core>(c, logging_on != FMI3_FALSE, n_categories, categories) }
        }

        // Creation and destruction of instances (section 2.3.1)

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi3InstantiateModelExchange(
            name: fmi3String,
            token: fmi3String,
            resource_path: fmi3String,
            _visible: fmi3Boolean, // no user interface to show
            logging_on: fmi3Boolean,
            environment: fmi3InstanceEnvironment,
            log_message: fmi3LogMessageCallback,
        ) -> fmi3Instance {
            unsafe {
                shell::instantiate::<$core>(shell::CRequest {
                    interface: InstanceKind::ModelExchange,
                    name,
                    token,
                    resource_path,
                    logging_on,
                    event_mode_used: FMI3_TRUE,
                    environment,
                    log_message,
                })
            }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi3InstantiateCoSimulation(
            name: fmi3String,
            token: fmi3String,
            resource_path: fmi3String,
            _visible: fmi3Boolean, // no user interface to show
            logging_on: fmi3Boolean,
            event_mode_used: fmi3Boolean,
            _early_return_allowed: fmi3Boolean, // the FMU never returns early
            _required_intermediate_variables: *const fmi3ValueReference,
            _n_required_intermediate_variables: usize, // no intermediate update
            environment: fmi3InstanceEnvironment,
            log_message: fmi3LogMessageCallback,
            _intermediate_update: fmi3IntermediateUpdateCallback,
        ) -> fmi3Instance {
            unsafe {
                shell::instantiate::<$core>(shell::CRequest {
                    interface: InstanceKind::CoSimulation,
                    name,
                    token,
                    resource_path,
                    logging_on,
                    event_mode_used,
                    environment,
                    log_message,
                })
            }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi3InstantiateScheduledExecution(
            _name: fmi3String,
            _token: fmi3String,
            _resource_path: fmi3String,
            _visible: fmi3Boolean,
            _logging_on: fmi3Boolean,
            environment: fmi3InstanceEnvironment,
            log_message: fmi3LogMessageCallback,
            _clock_update: fmi3ClockUpdateCallback,
            _lock_preemption: fmi3PreemptionCallback,
            _unlock_preemption: fmi3PreemptionCallback,
        ) -> fmi3Instance {
            let (f, what) = ("fmi3InstantiateScheduledExecution", "Scheduled Execution");
            unsafe { shell::instantiate_not_offered(f, what, environment, log_message) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi3FreeInstance(c: fmi3Instance) {
            unsafe { common::free_instance::<Fmi3, $core>(c) }
        }

        // Initialization, events, termination and reset (sections 2.3.2 to 2.3.5)

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi3EnterInitializationMode(
            c: fmi3Instance,
            tol_defined: fmi3Boolean,
            tol: fmi3Float64,
            start: fmi3Float64,
            stop_defined: fmi3Boolean,
            stop: fmi3Float64,
        ) -> fmi3Status {
            unsafe {
                shell::enter_initialization_mode::<$core>(c, tol_defined, tol, start, stop_defined, stop)
            }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi3ExitInitializationMode(c: fmi3Instance) -> fmi3Status {
            let f = "fmi3ExitInitializationMode";
            unsafe { common::simple::<Fmi3, $core>(c, f, Instance::exit_initialization_mode) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi3EnterEventMode(c: fmi3Instance) -> fmi3Status {
            unsafe { common::simple::<Fmi3, $core>(c, "fmi3EnterEventMode", Instance::enter_event_mode) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi3Terminate(c: fmi3Instance) -> fmi3Status {
            unsafe { common::simple::<Fmi3, $core>(c, "fmi3Terminate", Instance::terminate) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi3Reset(c: fmi3Instance) -> fmi3Status {
            unsafe { common::simple::<Fmi3, $core>(c, "fmi3Reset", Instance::reset) }
        }

        // Getting and setting variable values (section 2.3.3); Float64 variables only

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi3GetFloat64(
            c: fmi3Instance,
            vr: *const fmi3ValueReference,
            nvr: usize,
            values: *mut fmi3Float64,
            n_values: usize,
        ) -> fmi3Status {
            unsafe { common::get_values::<Fmi3, $core>(c, (vr, nvr), (values, n_values)) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi3SetFloat64(
            c: fmi3Instance,
            vr: *const fmi3ValueReference,
            nvr: usize,
            values: *const fmi3Float64,
            n_values: usize,
        ) -> fmi3Status {
            unsafe { common::set_values::<Fmi3, $core>(c, (vr, nvr), (values, n_values)) }
        }

        $crate::__fmi3_no_variables!([$($attr)*] $core, fmi3GetFloat32, fmi3SetFloat32, fmi3Float32);
        $crate::__fmi3_no_variables!([$($attr)*] $core, fmi3GetInt8, fmi3SetInt8, fmi3Int8);
        $crate::__fmi3_no_variables!([$($attr)*] $core, fmi3GetUInt8, fmi3SetUInt8, fmi3UInt8);
        $crate::__fmi3_no_variables!([$($attr)*] $core, fmi3GetInt16, fmi3SetInt16, fmi3Int16);
        $crate::__fmi3_no_variables!([$($attr)*] $core, fmi3GetUInt16, fmi3SetUInt16, fmi3UInt16);
        $crate::__fmi3_no_variables!([$($attr)*] $core, fmi3GetInt32, fmi3SetInt32, fmi3Int32);
        $crate::__fmi3_no_variables!([$($attr)*] $core, fmi3GetUInt32, fmi3SetUInt32, fmi3UInt32);
        $crate::__fmi3_no_variables!([$($attr)*] $core, fmi3GetInt64, fmi3SetInt64, fmi3Int64);
        $crate::__fmi3_no_variables!([$($attr)*] $core, fmi3GetUInt64, fmi3SetUInt64, fmi3UInt64);
        $crate::__fmi3_no_variables!([$($attr)*] $core, fmi3GetBoolean, fmi3SetBoolean, fmi3Boolean);
        $crate::__fmi3_no_variables!([$($attr)*] $core, fmi3GetString, fmi3SetString, fmi3String);

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi3GetBinary(
            c: fmi3Instance,
            vr: *const fmi3ValueReference,
            nvr: usize,
            _value_sizes: *mut usize,
            values: *mut fmi3Binary,
            _n_values: usize,
        ) -> fmi3Status {
            unsafe { common::no_variables::<Fmi3, $core>(c, "fmi3GetBinary", (vr, nvr), values.cast()) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi3SetBinary(
            c: fmi3Instance,
            vr: *const fmi3ValueReference,
            nvr: usize,
            _value_sizes: *const usize,
            values: *const fmi3Binary,
            _n_values: usize,
        ) -> fmi3Status {
            unsafe { common::no_variables::<Fmi3, $core>(c, "fmi3SetBinary", (vr, nvr), values.cast()) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi3GetClock(
            c: fmi3Instance,
            vr: *const fmi3ValueReference,
            nvr: usize,
            values: *mut fmi3Clock,
        ) -> fmi3Status {
            unsafe { common::no_variables::<Fmi3, $core>(c, "fmi3GetClock", (vr, nvr), values.cast()) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi3SetClock(
            c: fmi3Instance,
            vr: *const fmi3ValueReference,
            nvr: usize,
            values: *const fmi3Clock,
        ) -> fmi3Status {
            unsafe { common::no_variables::<Fmi3, $core>(c, "fmi3SetClock", (vr, nvr), values.cast()) }
        }

        // Variable dependency information (section 2.3.7): not offered

        $crate::__fmi3_not_offered!([$($attr)*] $core, fmi3GetNumberOfVariableDependencies, "providesPerElementDependencies",
            (_vr: fmi3ValueReference, _n: *mut usize));
        $crate::__fmi3_not_offered!([$($attr)*] $core, fmi3GetVariableDependencies, "providesPerElementDependencies",
            (_dependent: fmi3ValueReference, _element_indices_of_dependent: *mut usize,
             _independents: *mut fmi3ValueReference, _element_indices_of_independents: *mut usize,
             _dependency_kinds: *mut fmi3DependencyKind, _n: usize));

        // FMU states (section 2.3.6)

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi3GetFMUState(c: fmi3Instance, state: *mut fmi3FMUState) -> fmi3Status {
            unsafe { common::get_fmu_state::<Fmi3, $core>(c, "fmi3GetFMUState", state) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi3SetFMUState(c: fmi3Instance, state: fmi3FMUState) -> fmi3Status {
            unsafe { common::set_fmu_state::<Fmi3, $core>(c, "fmi3SetFMUState", state) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi3FreeFMUState(c: fmi3Instance, state: *mut fmi3FMUState) -> fmi3Status {
            unsafe { common::free_fmu_state::<Fmi3, $core>(c, "fmi3FreeFMUState", state) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi3SerializedFMUStateSize(
            c: fmi3Instance,
            state: fmi3FMUState,
            size: *mut usize,
        ) -> fmi3Status {
            unsafe { common::serialized_fmu_state_size::<Fmi3, $core>(c, "fmi3SerializedFMUStateSize", state, size) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi3SerializeFMUState(
            c: fmi3Instance,
            state: fmi3FMUState,
            bytes: *mut fmi3Byte,
            size: usize,
        ) -> fmi3Status {
            unsafe { common::serialize_fmu_state::<Fmi3, $core>(c, "fmi3SerializeFMUState", state, bytes.cast(), size) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi3DeserializeFMUState(
            c: fmi3Instance,
            bytes: *const fmi3Byte,
            size: usize,
            state: *mut fmi3FMUState,
        ) -> fmi3Status {
            unsafe { common::deserialize_fmu_state::<Fmi3, $core>(c, "fmi3DeserializeFMUState", bytes.cast(), size, state) }
        }

        // Partial derivatives (section 2.3.8)

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi3GetDirectionalDerivative(
            c: fmi3Instance,
            unknowns: *const fmi3ValueReference,
            n_unknowns: usize,
            knowns: *const fmi3ValueReference,
            n_knowns: usize,
            seed: *const fmi3Float64,
            n_seed: usize,
            sensitivity: *mut fmi3Float64,
            n_sensitivity: usize,
        ) -> fmi3Status {
            let arrays = common::DerivativeArrays {
                unknowns: (unknowns, n_unknowns),
                knowns: (knowns, n_knowns),
                seed: (seed, n_seed),
                sensitivity: (sensitivity, n_sensitivity),
            };
            let call = Instance::directional_derivative;
            unsafe { common::get_directional_derivative::<Fmi3, $core>(c, arrays, call) }
        }
        $crate::__fmi3_not_offered!([$($attr)*] $core, fmi3GetAdjointDerivative, "providesAdjointDerivatives",
            (_unknowns: *const fmi3ValueReference, _n_unknowns: usize,
             _knowns: *const fmi3ValueReference, _n_knowns: usize,
             _seed: *const fmi3Float64, _n_seed: usize,
             _sensitivity: *mut fmi3Float64, _n_sensitivity: usize));

        // Configuration Mode and Clocks (sections 2.3.2, 2.3.9): no structural parameters, no clocks

        $crate::__fmi3_not_offered!([$($attr)*] $core, fmi3EnterConfigurationMode, "Configuration Mode (structural parameters)", ());
        $crate::__fmi3_not_offered!([$($attr)*] $core, fmi3ExitConfigurationMode, "Configuration Mode (structural parameters)", ());
        $crate::__fmi3_not_offered!([$($attr)*] $core, fmi3GetIntervalDecimal, "Clocks",
            (_vr: *const fmi3ValueReference, _nvr: usize, _intervals: *mut fmi3Float64,
             _qualifiers: *mut fmi3IntervalQualifier));
        $crate::__fmi3_not_offered!([$($attr)*] $core, fmi3GetIntervalFraction, "Clocks",
            (_vr: *const fmi3ValueReference, _nvr: usize, _counters: *mut fmi3UInt64,
             _resolutions: *mut fmi3UInt64, _qualifiers: *mut fmi3IntervalQualifier));
        $crate::__fmi3_not_offered!([$($attr)*] $core, fmi3GetShiftDecimal, "Clocks",
            (_vr: *const fmi3ValueReference, _nvr: usize, _shifts: *mut fmi3Float64));
        $crate::__fmi3_not_offered!([$($attr)*] $core, fmi3GetShiftFraction, "Clocks",
            (_vr: *const fmi3ValueReference, _nvr: usize, _counters: *mut fmi3UInt64,
             _resolutions: *mut fmi3UInt64));
        $crate::__fmi3_not_offered!([$($attr)*] $core, fmi3SetIntervalDecimal, "Clocks",
            (_vr: *const fmi3ValueReference, _nvr: usize, _intervals: *const fmi3Float64));
        $crate::__fmi3_not_offered!([$($attr)*] $core, fmi3SetIntervalFraction, "Clocks",
            (_vr: *const fmi3ValueReference, _nvr: usize, _counters: *const fmi3UInt64,
             _resolutions: *const fmi3UInt64));
        $crate::__fmi3_not_offered!([$($attr)*] $core, fmi3SetShiftDecimal, "Clocks",
            (_vr: *const fmi3ValueReference, _nvr: usize, _shifts: *const fmi3Float64));
        $crate::__fmi3_not_offered!([$($attr)*] $core, fmi3SetShiftFraction, "Clocks",
            (_vr: *const fmi3ValueReference, _nvr: usize, _counters: *const fmi3UInt64,
             _resolutions: *const fmi3UInt64));
        $crate::__fmi3_not_offered!([$($attr)*] $core, fmi3EvaluateDiscreteStates, "providesEvaluateDiscreteStates", ());

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi3UpdateDiscreteStates(
            c: fmi3Instance,
            discrete_states_need_update: *mut fmi3Boolean,
            terminate_simulation: *mut fmi3Boolean,
            nominals_changed: *mut fmi3Boolean,
            values_changed: *mut fmi3Boolean,
            next_event_time_defined: *mut fmi3Boolean,
            next_event_time: *mut fmi3Float64,
        ) -> fmi3Status {
            unsafe {
                shell::update_discrete_states::<$core>(
                    c,
                    discrete_states_need_update,
                    terminate_simulation,
                    nominals_changed,
                    values_changed,
                    next_event_time_defined,
                    next_event_time,
                )
            }
        }

        // Model Exchange (section 3.2)

        $crate::__fmi3_model_exchange!([$($attr)*] $core);

        // Co-Simulation (section 4.2)

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi3EnterStepMode(c: fmi3Instance) -> fmi3Status {
            unsafe { common::simple::<Fmi3, $core>(c, "fmi3EnterStepMode", Instance::enter_step_mode) }
        }

        $crate::__fmi3_not_offered!([$($attr)*] $core, fmi3GetOutputDerivatives, "maxOutputDerivativeOrder > 0 (output derivatives)",
            (_vr: *const fmi3ValueReference, _nvr: usize, _orders: *const fmi3Int32,
             _values: *mut fmi3Float64, _n_values: usize));

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi3DoStep(
            c: fmi3Instance,
            tc: fmi3Float64,
            h: fmi3Float64,
            _no_set_fmu_state_prior: fmi3Boolean, // states are kept whole either way
            event_handling_needed: *mut fmi3Boolean,
            terminate_simulation: *mut fmi3Boolean,
            early_return: *mut fmi3Boolean,
            last_successful_time: *mut fmi3Float64,
        ) -> fmi3Status {
            unsafe {
                shell::do_step::<$core>(
                    c,
                    tc,
                    h,
                    event_handling_needed,
                    terminate_simulation,
                    early_return,
                    last_successful_time,
                )
            }
        }

        // Scheduled Execution (section 5.2): not offered

        $crate::__fmi3_not_offered!([$($attr)*] $core, fmi3ActivateModelPartition, "Scheduled Execution",
            (_clock: fmi3ValueReference, _activation_time: fmi3Float64));
    };
}

/// The Model Exchange functions of [`export_fmi3!`] (section 3.2).
#[doc(hidden)]
#[macro_export]
macro_rules! __fmi3_model_exchange {
    ([$($attr:tt)*] $core:ty) => {
        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi3EnterContinuousTimeMode(c: fmi3Instance) -> fmi3Status {
            let f = "fmi3EnterContinuousTimeMode";
            unsafe { common::simple::<Fmi3, $core>(c, f, Instance::enter_continuous_time_mode) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi3CompletedIntegratorStep(
            c: fmi3Instance,
            _no_set_fmu_state_prior: fmi3Boolean, // states are kept whole either way
            enter_event_mode: *mut fmi3Boolean,
            terminate_simulation: *mut fmi3Boolean,
        ) -> fmi3Status {
            unsafe { common::completed_integrator_step::<Fmi3, $core>(c, enter_event_mode, terminate_simulation) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi3SetTime(c: fmi3Instance, time: fmi3Float64) -> fmi3Status {
            unsafe { common::set_time::<Fmi3, $core>(c, time) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi3SetContinuousStates(
            c: fmi3Instance,
            x: *const fmi3Float64,
            nx: usize,
        ) -> fmi3Status {
            unsafe { common::set_continuous_states::<Fmi3, $core>(c, (x, nx), Instance::set_continuous_states) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi3GetContinuousStateDerivatives(
            c: fmi3Instance,
            dx: *mut fmi3Float64,
            nx: usize,
        ) -> fmi3Status {
            let names = ("fmi3GetContinuousStateDerivatives", shell::OUTPUT_ARRAY);
            let get = |inst: &mut Instance<$core>, out: &mut [f64]| inst.state_vector(names.0, out, |m, out| m.derivatives(out));
            unsafe { common::get_state_vector::<Fmi3, $core>(c, names, (dx, nx), get) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi3GetEventIndicators(
            c: fmi3Instance,
            z: *mut fmi3Float64,
            nz: usize,
        ) -> fmi3Status {
            unsafe { common::get_event_indicators::<Fmi3, $core>(c, (z, nz)) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi3GetContinuousStates(
            c: fmi3Instance,
            x: *mut fmi3Float64,
            nx: usize,
        ) -> fmi3Status {
            let names = ("fmi3GetContinuousStates", shell::OUTPUT_ARRAY);
            let get = |inst: &mut Instance<$core>, out: &mut [f64]| inst.state_vector(names.0, out, |m, out| m.continuous_states(out));
            unsafe { common::get_state_vector::<Fmi3, $core>(c, names, (x, nx), get) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi3GetNominalsOfContinuousStates(
            c: fmi3Instance,
            nominals: *mut fmi3Float64,
            nx: usize,
        ) -> fmi3Status {
            let names = ("fmi3GetNominalsOfContinuousStates", shell::OUTPUT_ARRAY);
            let get = |inst: &mut Instance<$core>, out: &mut [f64]| inst.state_vector(names.0, out, |m, out| m.nominals(out));
            unsafe { common::get_state_vector::<Fmi3, $core>(c, names, (nominals, nx), get) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi3GetNumberOfEventIndicators(
            c: fmi3Instance,
            n: *mut usize,
        ) -> fmi3Status {
            let f = "fmi3GetNumberOfEventIndicators";
            unsafe { shell::get_number_of::<$core>(c, f, n, |_| 0) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi3GetNumberOfContinuousStates(
            c: fmi3Instance,
            n: *mut usize,
        ) -> fmi3Status {
            let f = "fmi3GetNumberOfContinuousStates";
            unsafe { shell::get_number_of::<$core>(c, f, n, Instance::number_of_states) }
        }
    };
}

/// `fmi3Get…`/`fmi3Set…` of a type (`$t`) this FMU has no variables of.
#[doc(hidden)]
#[macro_export]
macro_rules! __fmi3_no_variables {
    ([$($attr:tt)*] $core:ty, $get:ident, $set:ident, $t:ty) => {
        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn $get(
            c: fmi3Instance,
            vr: *const fmi3ValueReference,
            nvr: usize,
            values: *mut $t,
            _n_values: usize,
        ) -> fmi3Status {
            unsafe { common::no_variables::<Fmi3, $core>(c, stringify!($get), (vr, nvr), values.cast()) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn $set(
            c: fmi3Instance,
            vr: *const fmi3ValueReference,
            nvr: usize,
            values: *const $t,
            _n_values: usize,
        ) -> fmi3Status {
            unsafe { common::no_variables::<Fmi3, $core>(c, stringify!($set), (vr, nvr), values.cast()) }
        }
    };
}

/// A function of a capability this FMU does not declare; `$what` says which.
#[doc(hidden)]
#[macro_export]
macro_rules! __fmi3_not_offered {
    ([$($attr:tt)*] $core:ty, $name:ident, $what:expr, ($($arg:ident: $t:ty),*)) => {
        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn $name(c: fmi3Instance, $($arg: $t),*) -> fmi3Status {
            unsafe { common::not_offered::<Fmi3, $core>(c, stringify!($name), $what) }
        }
    };
}
