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
        use $crate::fmi3::types::*;

        // Inquire version number (section 2.3.1)

        $($attr)* #[allow(non_snake_case)]
        pub extern "C" fn fmi3GetVersion() -> *const ::std::ffi::c_char {
            shell::version()
        }

        // Debug logging, freeing an instance, and the calls without arguments (sections 2.3.1 to
        // 2.3.5)

        $crate::__fmi_lifecycle_functions!([$($attr)*] $core, Fmi3, fmi3Instance, fmi3Status, fmi3Boolean, fmi3String,
            [fmi3SetDebugLogging, fmi3FreeInstance],
            [fmi3ExitInitializationMode: exit_initialization_mode, fmi3Terminate: terminate, fmi3Reset: reset,
             fmi3EnterEventMode: enter_event_mode]);

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

        $crate::__fmi_no_variables_functions!([$($attr)*] $core, Fmi3, fmi3Instance, fmi3Status, fmi3ValueReference,
            [(fmi3GetClock, fmi3SetClock, fmi3Clock)]);

        // Variable dependency information (section 2.3.7): not offered

        $crate::__fmi3_not_offered!([$($attr)*] $core, fmi3GetNumberOfVariableDependencies, "providesPerElementDependencies",
            (_vr: fmi3ValueReference, _n: *mut usize));
        $crate::__fmi3_not_offered!([$($attr)*] $core, fmi3GetVariableDependencies, "providesPerElementDependencies",
            (_dependent: fmi3ValueReference, _element_indices_of_dependent: *mut usize,
             _independents: *mut fmi3ValueReference, _element_indices_of_independents: *mut usize,
             _dependency_kinds: *mut fmi3DependencyKind, _n: usize));

        // FMU states (section 2.3.6)

        $crate::__fmi_fmu_state_functions!([$($attr)*] $core, Fmi3, fmi3Instance, fmi3Status, fmi3FMUState, fmi3Byte,
            [fmi3GetFMUState, fmi3SetFMUState, fmi3FreeFMUState, fmi3SerializedFMUStateSize, fmi3SerializeFMUState,
             fmi3DeserializeFMUState]);

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
        $crate::__fmi_model_exchange_functions!([$($attr)*] $core, Fmi3, fmi3Instance, fmi3Status, fmi3Boolean,
            [fmi3EnterContinuousTimeMode, fmi3CompletedIntegratorStep, fmi3SetTime, fmi3SetContinuousStates,
             fmi3GetEventIndicators],
            [(fmi3GetContinuousStateDerivatives, "the output array", get_derivatives),
             (fmi3GetContinuousStates, "the output array", get_continuous_states),
             (fmi3GetNominalsOfContinuousStates, "the output array", get_nominals)]);

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
