//! The Model Exchange calls of the generic [`Instance`] that FMI 2.0 and 3.0 define alike
//! (FMI 2.0 section 3.2, FMI 3.0 section 3.2), worded by the version's [`Names`] and
//! [`Wording`] and checked against its [`Masks`]. The calls on the state vector and the
//! directional derivative check their arguments each version its own way and stay in the
//! version's instance.
//!
//! [`Names`]: super::instance::Names
//! [`Wording`]: super::instance::Wording
//! [`Masks`]: super::instance::Masks

use super::instance::{Instance, Version, fill};
use super::logging::Status;
use super::model_api::{FmuCore, InstanceKind};

impl<V: Version, M: FmuCore> Instance<V, M> {
    /// `fmiXSetTime`: the time of the next evaluations, finite.
    pub fn set_time(&mut self, time: f64) -> Status {
        let func = V::NAMES.set_time;
        self.trace(|| format!("{func}(time={time:?})"));
        if let Err(s) = self.require_of(func, InstanceKind::ModelExchange, V::MASKS.set_time) {
            return s;
        }
        if !time.is_finite() {
            return self.error(func, format_args!("time = {time:?} is not finite"));
        }
        match self.core.set_time(time) {
            Ok(()) => Status::Ok,
            Err(msg) => self.error(func, format_args!("time = {time:?}: {msg}")),
        }
    }

    /// `fmiXGetEventIndicators`: the FMU has none (`numberOfEventIndicators` is 0), so the
    /// importer's count `n` must be 0.
    pub fn event_indicators(&self, n: usize) -> Status {
        let func = V::NAMES.get_event_indicators;
        let mask = V::MASKS.get_event_indicators;
        if let Err(s) = self.require_of(func, InstanceKind::ModelExchange, mask) {
            return s;
        }
        if n != 0 {
            let count = n.to_string();
            return self.error(func, fill(V::WORDING.no_event_indicators, [&count, ""]));
        }
        Status::Ok
    }

    /// `fmiXCompletedIntegratorStep`: no step event, no termination. Returns
    /// `(enterEventMode, terminateSimulation)`.
    pub fn completed_integrator_step(&mut self) -> Result<(bool, bool), Status> {
        let func = V::NAMES.completed_integrator_step;
        let mask = V::MASKS.completed_integrator_step;
        self.require_of(func, InstanceKind::ModelExchange, mask)?;
        Ok((false, false))
    }
}
