//! The `extern "C"` functions FMI 2.0 and 3.0 declare alike but for their names and C types,
//! written once for both versions' macros ([`export_fmi2!`](crate::export_fmi2),
//! [`export_fmi3!`](crate::export_fmi3)): each takes the bracketed attributes to put on every
//! function, the core, the version (`Fmi2`, `Fmi3`), its C types and the functions' names, and
//! hands the arguments to the body of the same name in [`calls`](super::calls).

/// `fmiXSetDebugLogging`, `fmiXFreeInstance`, and the calls without arguments of both versions
/// (`fmiXExitInitializationMode`, `fmiXTerminate`, `fmiXReset`, `fmiXEnterEventMode`).
#[doc(hidden)]
#[macro_export]
macro_rules! __fmi_lifecycle_functions {
    ($attrs:tt $core:ty, $v:ty, $instance:ty, $status:ty, $boolean:ty, $string:ty,
     [$set_debug_logging:ident, $free_instance:ident],
     [$($simple:ident: $method:ident),*]) => {
        $crate::__fmi_with_attributes! { $attrs
            #[allow(non_snake_case, clippy::missing_safety_doc)]
            pub unsafe extern "C" fn $set_debug_logging(
                c: $instance,
                logging_on: $boolean,
                n_categories: usize,
                categories: *const $string,
            ) -> $status {
                let on = logging_on != <$boolean>::from(false);
                unsafe { $crate::fmi_common::calls::set_debug_logging::<$v, $core>(c, on, n_categories, categories) }
            }
        }

        $crate::__fmi_with_attributes! { $attrs
            #[allow(non_snake_case, clippy::missing_safety_doc)]
            pub unsafe extern "C" fn $free_instance(c: $instance) {
                unsafe { $crate::fmi_common::calls::free_instance::<$v, $core>(c) }
            }
        }

        $(
            $crate::__fmi_with_attributes! { $attrs
                #[allow(non_snake_case, clippy::missing_safety_doc)]
                pub unsafe extern "C" fn $simple(c: $instance) -> $status {
                    let call = $crate::fmi_common::instance::Instance::<$v, $core>::$method;
                    unsafe { $crate::fmi_common::calls::simple::<$v, $core>(c, stringify!($simple), call) }
                }
            }
        )*
    };
}

/// The getters and setters of the types this FMU has no variables of, of the one signature
/// `(instance, valueReferences, nValueReferences, values)`: `(getter, setter, C type)` each.
#[doc(hidden)]
#[macro_export]
macro_rules! __fmi_no_variables_functions {
    ($attrs:tt $core:ty, $v:ty, $instance:ty, $status:ty, $reference:ty,
     [$(($get:ident, $set:ident, $t:ty)),*]) => {
        $(
            $crate::__fmi_with_attributes! { $attrs
                #[allow(non_snake_case, clippy::missing_safety_doc)]
                pub unsafe extern "C" fn $get(c: $instance, vr: *const $reference, nvr: usize, values: *mut $t) -> $status {
                    let f = stringify!($get);
                    unsafe { $crate::fmi_common::calls::no_variables::<$v, $core>(c, f, (vr, nvr), values.cast()) }
                }
            }

            $crate::__fmi_with_attributes! { $attrs
                #[allow(non_snake_case, clippy::missing_safety_doc)]
                pub unsafe extern "C" fn $set(c: $instance, vr: *const $reference, nvr: usize, values: *const $t) -> $status {
                    let f = stringify!($set);
                    unsafe { $crate::fmi_common::calls::no_variables::<$v, $core>(c, f, (vr, nvr), values.cast()) }
                }
            }
        )*
    };
}

/// The six FMU-state functions: get, set, free, size, serialize, deserialize.
#[doc(hidden)]
#[macro_export]
macro_rules! __fmi_fmu_state_functions {
    ($attrs:tt $core:ty, $v:ty, $instance:ty, $status:ty, $state:ty, $byte:ty,
     [$get:ident, $set:ident, $free:ident, $size:ident, $serialize:ident, $deserialize:ident]) => {
        $crate::__fmi_with_attributes! { $attrs
            #[allow(non_snake_case, clippy::missing_safety_doc)]
            pub unsafe extern "C" fn $get(c: $instance, state: *mut $state) -> $status {
                unsafe { $crate::fmi_common::calls::get_fmu_state::<$v, $core>(c, stringify!($get), state) }
            }
        }

        $crate::__fmi_with_attributes! { $attrs
            #[allow(non_snake_case, clippy::missing_safety_doc)]
            pub unsafe extern "C" fn $set(c: $instance, state: $state) -> $status {
                unsafe { $crate::fmi_common::calls::set_fmu_state::<$v, $core>(c, stringify!($set), state) }
            }
        }

        $crate::__fmi_with_attributes! { $attrs
            #[allow(non_snake_case, clippy::missing_safety_doc)]
            pub unsafe extern "C" fn $free(c: $instance, state: *mut $state) -> $status {
                unsafe { $crate::fmi_common::calls::free_fmu_state::<$v, $core>(c, stringify!($free), state) }
            }
        }

        $crate::__fmi_with_attributes! { $attrs
            #[allow(non_snake_case, clippy::missing_safety_doc)]
            pub unsafe extern "C" fn $size(c: $instance, state: $state, size: *mut usize) -> $status {
                let f = stringify!($size);
                unsafe { $crate::fmi_common::calls::serialized_fmu_state_size::<$v, $core>(c, f, state, size) }
            }
        }

        $crate::__fmi_with_attributes! { $attrs
            #[allow(non_snake_case, clippy::missing_safety_doc)]
            pub unsafe extern "C" fn $serialize(
                c: $instance,
                state: $state,
                bytes: *mut $byte,
                size: usize,
            ) -> $status {
                let f = stringify!($serialize);
                unsafe { $crate::fmi_common::calls::serialize_fmu_state::<$v, $core>(c, f, state, bytes.cast(), size) }
            }
        }

        $crate::__fmi_with_attributes! { $attrs
            #[allow(non_snake_case, clippy::missing_safety_doc)]
            pub unsafe extern "C" fn $deserialize(
                c: $instance,
                bytes: *const $byte,
                size: usize,
                state: *mut $state,
            ) -> $status {
                let f = stringify!($deserialize);
                unsafe { $crate::fmi_common::calls::deserialize_fmu_state::<$v, $core>(c, f, bytes.cast(), size, state) }
            }
        }
    };
}

/// The Model Exchange functions both versions declare alike: Continuous-Time Mode, the
/// completed integrator step, time, states, event indicators, and the three getters of the
/// state vector, each `(function, its array argument's name in NULL messages, instance
/// method)`.
#[doc(hidden)]
#[macro_export]
macro_rules! __fmi_model_exchange_functions {
    ($attrs:tt $core:ty, $v:ty, $instance:ty, $status:ty, $boolean:ty,
     [$enter_continuous_time_mode:ident, $completed_integrator_step:ident, $set_time:ident,
      $set_continuous_states:ident, $get_event_indicators:ident],
     [$(($get:ident, $argument:literal, $method:ident)),*]) => {
        $crate::__fmi_with_attributes! { $attrs
            #[allow(non_snake_case, clippy::missing_safety_doc)]
            pub unsafe extern "C" fn $enter_continuous_time_mode(c: $instance) -> $status {
                let call = $crate::fmi_common::instance::Instance::<$v, $core>::enter_continuous_time_mode;
                let f = stringify!($enter_continuous_time_mode);
                unsafe { $crate::fmi_common::calls::simple::<$v, $core>(c, f, call) }
            }
        }

        $crate::__fmi_with_attributes! { $attrs
            #[allow(non_snake_case, clippy::missing_safety_doc)]
            pub unsafe extern "C" fn $completed_integrator_step(
                c: $instance,
                _no_set_fmu_state_prior: $boolean, // states are kept whole either way
                enter_event_mode: *mut $boolean,
                terminate_simulation: *mut $boolean,
            ) -> $status {
                let (event, terminate) = (enter_event_mode, terminate_simulation);
                unsafe { $crate::fmi_common::calls::completed_integrator_step::<$v, $core>(c, event, terminate) }
            }
        }

        $crate::__fmi_with_attributes! { $attrs
            #[allow(non_snake_case, clippy::missing_safety_doc)]
            pub unsafe extern "C" fn $set_time(c: $instance, time: f64) -> $status {
                unsafe { $crate::fmi_common::calls::set_time::<$v, $core>(c, time) }
            }
        }

        $crate::__fmi_with_attributes! { $attrs
            #[allow(non_snake_case, clippy::missing_safety_doc)]
            pub unsafe extern "C" fn $set_continuous_states(c: $instance, x: *const f64, nx: usize) -> $status {
                let call = $crate::fmi_common::instance::Instance::<$v, $core>::set_continuous_states;
                unsafe { $crate::fmi_common::calls::set_continuous_states::<$v, $core>(c, (x, nx), call) }
            }
        }

        $crate::__fmi_with_attributes! { $attrs
            #[allow(non_snake_case, clippy::missing_safety_doc)]
            pub unsafe extern "C" fn $get_event_indicators(c: $instance, indicators: *mut f64, n: usize) -> $status {
                unsafe { $crate::fmi_common::calls::get_event_indicators::<$v, $core>(c, (indicators, n)) }
            }
        }

        $(
            $crate::__fmi_with_attributes! { $attrs
                #[allow(non_snake_case, clippy::missing_safety_doc)]
                pub unsafe extern "C" fn $get(c: $instance, out: *mut f64, nx: usize) -> $status {
                    let names = (stringify!($get), $argument);
                    let call = $crate::fmi_common::instance::Instance::<$v, $core>::$method;
                    unsafe { $crate::fmi_common::calls::get_state_vector::<$v, $core>(c, names, (out, nx), call) }
                }
            }
        )*
    };
}

/// The item after the bracketed attributes, with the attributes put on it: how the macros above
/// put them on functions inside a repetition of their own.
#[doc(hidden)]
#[macro_export]
macro_rules! __fmi_with_attributes {
    ([$($attr:tt)*] $($item:tt)*) => {
        $($attr)* $($item)*
    };
}
