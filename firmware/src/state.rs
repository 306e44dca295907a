//! Every state of the head and every event that moves it, in one table.
//!
//! The head serves one operation at a time; what may run, whether the laser
//! may stay on and whether the drivers hold the motors all follow from the
//! state, and every change of state goes through [`transition`]. A stop
//! (abort, link loss, host silence, E-STOP) switches the laser off in the
//! transition itself, before the motion is even braked; the deceleration
//! then runs in [`Mode::Stopping`], and [`Event::Stopped`] ends it in the
//! state the stop asked for.

use gonio_shared::Fault;

/// Where a stop leaves the head once the motion stands.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Rest {
    /// Nothing held: ready for the next request.
    Idle,
    /// A scan is held at its next position, to continue without replanning.
    Paused,
    /// E-STOP: everything refused until the input is closed again and the
    /// host asks to continue.
    Faulted,
}

/// What the head is doing.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    Idle,
    Homing,
    Moving,
    /// A single measurement or the reference learned (laser on).
    Measuring,
    Scanning,
    /// A scan is held; moves and measurements (a drift-monitor visit) are
    /// served without leaving it.
    Paused,
    /// The motion decelerates after a stop; the laser is already off.
    Stopping(Rest),
    Faulted,
}

/// What happens to the head.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Event {
    // Requests.
    Home,
    Move,
    /// A measurement or the reference learned, moving first when asked to.
    Measure,
    Scan,
    Pause,
    Continue,
    Abort,
    // Ends of operations.
    /// The operation (or the scan) ended as asked.
    Done,
    /// The operation ended with a fault of its own (stall, ADC overrun, ...).
    Failed,
    // Stops from outside the operation.
    LinkLost,
    HostSilent,
    EStop,
    /// The deceleration after a stop has ended.
    Stopped,
    /// No request for the idle time: the drivers let go.
    IdleTimeout,
    /// The laser's idle time at rest has passed.
    LaserIdle,
}

/// The laser enable, as a transition leaves it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Laser {
    /// Low at once (and the chop stopped).
    Off,
    /// As it was: an operation switches it on when it measures.
    Keep,
}

/// The motor drivers, as a transition leaves them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Drivers {
    /// Enabled before anything moves.
    Enable,
    /// Disabled: the motors hold by detent (and the worm gears) only.
    Disable,
    Keep,
}

/// The outcome of one event in one state.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Transition {
    pub to: Mode,
    pub laser: Laser,
    pub drivers: Drivers,
    /// The request is refused with this fault (and nothing changes).
    pub refused: Option<Fault>,
}

impl Mode {
    /// Every state, for exhaustive tests.
    pub const ALL: [Mode; 10] = [
        Mode::Idle,
        Mode::Homing,
        Mode::Moving,
        Mode::Measuring,
        Mode::Scanning,
        Mode::Paused,
        Mode::Stopping(Rest::Idle),
        Mode::Stopping(Rest::Paused),
        Mode::Stopping(Rest::Faulted),
        Mode::Faulted,
    ];

    /// An operation is running (and may be moving the stages).
    pub fn busy(self) -> bool {
        matches!(
            self,
            Mode::Homing | Mode::Moving | Mode::Measuring | Mode::Scanning | Mode::Stopping(_)
        )
    }

    /// The laser may be on in this state.
    pub fn laser_allowed(self) -> bool {
        matches!(self, Mode::Measuring | Mode::Scanning | Mode::Paused | Mode::Idle)
    }
}

impl Event {
    pub const ALL: [Event; 15] = [
        Event::Home,
        Event::Move,
        Event::Measure,
        Event::Scan,
        Event::Pause,
        Event::Continue,
        Event::Abort,
        Event::Done,
        Event::Failed,
        Event::LinkLost,
        Event::HostSilent,
        Event::EStop,
        Event::Stopped,
        Event::IdleTimeout,
        Event::LaserIdle,
    ];
}

const fn go(to: Mode, laser: Laser, drivers: Drivers) -> Transition {
    Transition {
        to,
        laser,
        drivers,
        refused: None,
    }
}

const fn refuse(state: Mode, why: Fault) -> Transition {
    Transition {
        to: state,
        laser: Laser::Keep,
        drivers: Drivers::Keep,
        refused: Some(why),
    }
}

/// The table: what `event` does in state `s`.
pub fn transition(s: Mode, event: Event) -> Transition {
    use Drivers::{Disable, Enable, Keep as Hold};
    use Event as E;
    use Laser::{Keep, Off};
    use Mode as M;
    let stay = go(s, Keep, Hold);
    match (s, event) {
        // Requests at rest start their operation, drivers on; in a pause the
        // stages may be visited without leaving it.
        // A laser left on by its idle time goes off for homing and moves.
        (M::Idle, E::Home) => go(M::Homing, Off, Enable),
        (M::Idle, E::Move) => go(M::Moving, Off, Enable),
        (M::Idle, E::Measure) => go(M::Measuring, Keep, Enable),
        (M::Idle | M::Paused, E::Scan) => go(M::Scanning, Keep, Enable),
        (M::Paused, E::Move | E::Measure) => go(M::Paused, Keep, Enable),
        (M::Paused, E::Home) => refuse(s, Fault::Busy),
        (M::Paused, E::Continue) => go(M::Scanning, Keep, Enable),
        (M::Idle, E::Pause | E::Continue) => refuse(s, Fault::NotScanning),
        (M::Faulted, E::Home | E::Move | E::Measure | E::Scan | E::Pause) => refuse(s, Fault::EmergencyStop),
        // Continue re-arms after an E-STOP (the head checks the input first).
        (M::Faulted, E::Continue) => go(M::Idle, Off, Disable),
        (M::Scanning, E::Pause) => go(M::Stopping(Rest::Paused), Off, Hold),
        (M::Paused | M::Stopping(_), E::Pause) => stay,
        (_, E::Home | E::Move | E::Measure | E::Scan | E::Pause | E::Continue) => refuse(s, Fault::Busy),
        // Abort: stop whatever runs and drop a held scan. A pause may be
        // moving (a drift-monitor visit): its stops brake like the others.
        (M::Homing | M::Moving | M::Measuring | M::Scanning | M::Paused | M::Stopping(Rest::Idle | Rest::Paused), E::Abort) => {
            go(M::Stopping(Rest::Idle), Off, Hold)
        }
        (M::Idle, E::Abort) => go(M::Idle, Off, Disable),
        (M::Stopping(Rest::Faulted) | M::Faulted, E::Abort) => go(s, Off, Hold),
        // Link loss and host silence: a scan is held, anything else dropped.
        (M::Scanning | M::Paused, E::LinkLost | E::HostSilent) => go(M::Stopping(Rest::Paused), Off, Hold),
        (M::Homing | M::Moving | M::Measuring, E::LinkLost | E::HostSilent) => go(M::Stopping(Rest::Idle), Off, Hold),
        (M::Idle | M::Faulted, E::LinkLost | E::HostSilent) => go(s, Off, Disable),
        (M::Stopping(_), E::LinkLost | E::HostSilent) => go(s, Off, Hold),
        // E-STOP: from anywhere, laser off now, motion braked, then faulted.
        (M::Idle | M::Faulted, E::EStop) => go(M::Faulted, Off, Disable),
        (_, E::EStop) => go(M::Stopping(Rest::Faulted), Off, Hold),
        // Ends of operations; a measurement leaves the laser to its idle time.
        (M::Measuring, E::Done) => go(M::Idle, Keep, Hold),
        (M::Homing | M::Moving | M::Scanning, E::Done) => go(M::Idle, Off, Hold),
        (M::Homing | M::Moving | M::Measuring | M::Scanning, E::Failed) => go(M::Idle, Off, Disable),
        (M::Paused, E::Failed) => go(M::Paused, Off, Disable),
        (_, E::Done | E::Failed) => stay,
        (M::Stopping(Rest::Idle), E::Stopped) => go(M::Idle, Off, Disable),
        (M::Stopping(Rest::Paused), E::Stopped) => go(M::Paused, Off, Disable),
        (M::Stopping(Rest::Faulted), E::Stopped) => go(M::Faulted, Off, Disable),
        (_, E::Stopped) => stay,
        (M::Idle | M::Paused, E::IdleTimeout) => go(s, Off, Disable),
        (_, E::IdleTimeout) => stay,
        (M::Idle | M::Paused, E::LaserIdle) => go(s, Off, Hold),
        (_, E::LaserIdle) => stay,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Nothing can be moving: a pause may be (a drift-monitor visit).
    fn at_rest(s: Mode) -> bool {
        matches!(s, Mode::Idle | Mode::Faulted)
    }

    fn stop_trigger(e: Event) -> bool {
        matches!(e, Event::Abort | Event::LinkLost | Event::HostSilent | Event::EStop)
    }

    /// The table again, written as the rules docs/faults.md states, not as
    /// a match on pairs: what every pair must give.
    fn expected(s: Mode, e: Event) -> Transition {
        use Drivers::{Disable, Enable};
        use Laser::{Keep, Off};
        let refuse = |f| Transition {
            to: s,
            laser: Keep,
            drivers: Drivers::Keep,
            refused: Some(f),
        };
        let go = |to, laser, drivers| Transition {
            to,
            laser,
            drivers,
            refused: None,
        };
        let request = matches!(
            e,
            Event::Home | Event::Move | Event::Measure | Event::Scan | Event::Pause | Event::Continue
        );
        if stop_trigger(e) {
            // Every stop darkens the laser at once, from any state.
            let to = match (e, s) {
                (Event::EStop, _) if at_rest(s) => Mode::Faulted,
                (Event::EStop, _) => Mode::Stopping(Rest::Faulted),
                (_, Mode::Faulted | Mode::Stopping(Rest::Faulted)) => s,
                (Event::Abort, _) if at_rest(s) => Mode::Idle,
                (Event::Abort, _) => Mode::Stopping(Rest::Idle),
                (_, Mode::Scanning | Mode::Paused) => Mode::Stopping(Rest::Paused),
                (_, Mode::Stopping(_)) => s,
                (_, _) if at_rest(s) => s,
                _ => Mode::Stopping(Rest::Idle),
            };
            // Drivers let go only where nothing moves; a brake needs them.
            let drivers = if at_rest(s) && !(e == Event::Abort && s == Mode::Faulted) {
                Disable
            } else {
                Drivers::Keep
            };
            return go(to, Off, drivers);
        }
        if request {
            if s == Mode::Faulted {
                return if e == Event::Continue {
                    go(Mode::Idle, Off, Disable)
                } else {
                    refuse(Fault::EmergencyStop)
                };
            }
            return match (s, e) {
                (Mode::Idle, Event::Pause | Event::Continue) => refuse(Fault::NotScanning),
                (Mode::Idle, Event::Home) => go(Mode::Homing, Off, Enable),
                (Mode::Idle, Event::Move) => go(Mode::Moving, Off, Enable),
                (Mode::Idle, Event::Measure) => go(Mode::Measuring, Keep, Enable),
                (Mode::Idle | Mode::Paused, Event::Scan) | (Mode::Paused, Event::Continue) => go(Mode::Scanning, Keep, Enable),
                (Mode::Paused, Event::Move | Event::Measure) => go(Mode::Paused, Keep, Enable),
                (Mode::Scanning, Event::Pause) => go(Mode::Stopping(Rest::Paused), Off, Drivers::Keep),
                (Mode::Paused | Mode::Stopping(_), Event::Pause) => go(s, Keep, Drivers::Keep),
                _ => refuse(Fault::Busy),
            };
        }
        let running = matches!(s, Mode::Homing | Mode::Moving | Mode::Measuring | Mode::Scanning);
        match e {
            Event::Done if s == Mode::Measuring => go(Mode::Idle, Keep, Drivers::Keep),
            Event::Done if running => go(Mode::Idle, Off, Drivers::Keep),
            Event::Failed if running || s == Mode::Paused => go(if running { Mode::Idle } else { s }, Off, Disable),
            Event::Stopped => match s {
                Mode::Stopping(Rest::Idle) => go(Mode::Idle, Off, Disable),
                Mode::Stopping(Rest::Paused) => go(Mode::Paused, Off, Disable),
                Mode::Stopping(Rest::Faulted) => go(Mode::Faulted, Off, Disable),
                _ => go(s, Keep, Drivers::Keep),
            },
            Event::IdleTimeout if matches!(s, Mode::Idle | Mode::Paused) => go(s, Off, Disable),
            Event::LaserIdle if matches!(s, Mode::Idle | Mode::Paused) => go(s, Off, Drivers::Keep),
            _ => go(s, Keep, Drivers::Keep),
        }
    }

    #[test]
    fn every_state_and_event_gives_the_documented_outcome() {
        let mut pairs = 0;
        for s in Mode::ALL {
            for e in Event::ALL {
                let t = transition(s, e);
                assert_eq!(t, expected(s, e), "{s:?} × {e:?}");
                pairs += 1;
            }
        }
        assert_eq!(pairs, Mode::ALL.len() * Event::ALL.len());
    }

    #[test]
    fn invariants_hold_over_the_whole_table() {
        for s in Mode::ALL {
            for e in Event::ALL {
                let t = transition(s, e);
                if t.refused.is_some() {
                    assert_eq!(
                        (t.to, t.laser, t.drivers),
                        (s, Laser::Keep, Drivers::Keep),
                        "{s:?} × {e:?}: a refusal changed something"
                    );
                }
                // Motion never loses its drivers: a state that may move keeps them.
                if t.to.busy() {
                    assert_ne!(t.drivers, Drivers::Disable, "{s:?} × {e:?}");
                }
                // A stop from a state that may be moving goes through Stopping.
                if stop_trigger(e) && (s.busy() || s == Mode::Paused) {
                    assert!(matches!(t.to, Mode::Stopping(_)), "{s:?} × {e:?} → {:?}", t.to);
                }
                // Only continue leaves an E-STOP, and only the E-STOP enters it.
                if s == Mode::Faulted && t.to != Mode::Faulted {
                    assert_eq!(e, Event::Continue);
                }
                if t.to == Mode::Faulted && s != Mode::Faulted {
                    assert!(matches!(e, Event::EStop | Event::Stopped), "{s:?} × {e:?}");
                }
                // Where the laser may not be on, the transition into it darkens it.
                if !t.to.laser_allowed() && t.refused.is_none() && t.to != s {
                    assert!(t.laser == Laser::Off || !s.laser_allowed(), "{s:?} × {e:?}");
                }
            }
        }
    }
}
