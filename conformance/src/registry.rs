//! What a named check is ([`Check`]: a name, a [`Group`], the function of one FMI version) and
//! the `registry!` macro that lists the checks of one version: the room below both versions'
//! check lists ([`crate::checks`] for FMI 2.0, [`crate::fmi3::checks`] for FMI 3.0), so that
//! neither imports the other's module for it.

use crate::outcome::{Findings, Outcome, capture};
use crate::{Fmu, Fmu3, Loaded, Version};

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Group {
    Calls,
    StateMachine,
    FmuState,
    Instances,
    Memory,
    RandomSequences,
    Native,
    ModelExchange,
    DirectionalDerivatives,
}

impl Group {
    pub const ALL: [Group; 9] = [
        Group::Calls,
        Group::StateMachine,
        Group::FmuState,
        Group::Instances,
        Group::Memory,
        Group::RandomSequences,
        Group::Native,
        Group::ModelExchange,
        Group::DirectionalDerivatives,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Group::Calls => "calls",
            Group::StateMachine => "state machine",
            Group::FmuState => "FMU state",
            Group::Instances => "instances/threads",
            Group::Memory => "memory",
            Group::RandomSequences => "random sequences",
            Group::Native => "native C host/valgrind",
            Group::ModelExchange => "model exchange",
            Group::DirectionalDerivatives => "directional derivatives",
        }
    }
}

impl std::fmt::Display for Group {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A check's function, of the FMI version it checks.
#[derive(Clone, Copy)]
pub enum Run {
    Fmi2(fn(&Fmu)),
    Fmi3(fn(&Fmu3)),
}

/// A named check.
#[derive(Clone, Copy)]
pub struct Check {
    pub name: &'static str,
    pub group: Group,
    pub run: Run,
}

impl std::fmt::Debug for Check {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} ({})", self.name, self.group)
    }
}

impl Check {
    /// The FMI version of the FMUs this check checks.
    pub fn version(&self) -> Version {
        match self.run {
            Run::Fmi2(_) => Version::Fmi2,
            Run::Fmi3(_) => Version::Fmi3,
        }
    }

    /// Runs the check on `fmu` in this process (panics are caught). Panics when the check is
    /// of the other FMI version.
    pub fn run_on<F: Checked>(&self, fmu: &F) -> (Outcome, Findings) {
        let run = F::check_fn(self.run)
            .unwrap_or_else(|| panic!("{} checks {:?} FMUs, not {:?}", self.name, self.version(), F::VERSION));
        crate::calllog::begin();
        let (outcome, mut findings) = capture(|| {
            fmu.runnable(self.name);
            run(fmu)
        });
        // A check that only warned: the calls up to its first warning's (a failure under
        // --strict, and an importer's mistake the vendor may want to see refused).
        if let Outcome::Warn(m) = &outcome
            && self.group != Group::RandomSequences
            && let Some(first) = findings.warnings.first_mut()
            && let Some(warned) = crate::calllog::take_warned().filter(|(log, _)| log.replayable())
        {
            let note = crate::replay::write::write_check_reproducer(
                fmu.id(),
                fmu.archive(),
                F::VERSION,
                self.name,
                first,
                &warned,
                true,
            );
            first.push_str(&format!("\n{note}"));
            return (Outcome::Warn(format!("{m}\n{note}")), findings);
        }
        let failing = crate::calllog::take_failing();
        let outcome = match outcome {
            // The random checks write their own (shrunk) reproducers.
            Outcome::Fail(m)
                if self.group != Group::RandomSequences && !m.contains(crate::replay::write::REPRODUCER_SENTENCE) =>
            {
                match failing {
                    Some((log, _)) if !log.replayable() => Outcome::Fail(format!(
                        "{m}\nno reproducer: the check failed on an instance the replay does not make ({})",
                        log.instantiate.as_ref().map_or("", |i| &*i.function)
                    )),
                    Some(failed) => {
                        let note = crate::replay::write::write_check_reproducer(
                            fmu.id(),
                            fmu.archive(),
                            F::VERSION,
                            self.name,
                            &m,
                            &failed,
                            false,
                        );
                        Outcome::Fail(format!("{m}\n{note}"))
                    }
                    None => Outcome::Fail(m),
                }
            }
            other => other,
        };
        (outcome, findings)
    }

    /// Whether a filter selects this check: a substring of its name or of its group's name.
    pub fn matches(&self, filter: &str) -> bool {
        self.name.contains(filter) || self.group.name().contains(filter)
    }

    /// Its line in `fmu-check --list`: `group / name`, with `FMI 3.0: ` before an FMI 3.0 check.
    pub fn list_line(&self) -> String {
        match self.version() {
            Version::Fmi2 => format!("{} / {}", self.group, self.name),
            Version::Fmi3 => format!("FMI 3.0: {} / {}", self.group, self.name),
        }
    }
}

/// `const NAME = version { group: module::{check, ...}; ... }`: the checks of one FMI version
/// (the FMI 2.0 ones in [`crate::checks`], the FMI 3.0 ones in [`crate::fmi3::checks`]), by group, in report
/// order; [`crate::checks::all_checks`] lists both.
macro_rules! registry {
    ($(#[$doc:meta])* const $list:ident = $version:ident {$($group:ident: $module:ident::{$($name:ident),* $(,)?};)*}) => {
        $(#[$doc])*
        pub(crate) const $list: &[$crate::registry::Check] = &[$($($crate::registry::Check {
            name: stringify!($name),
            group: $crate::registry::Group::$group,
            run: $crate::registry::Run::$version($module::$name),
        },)*)*];
    };
}
pub(crate) use registry;

/// A kind of FMU the checks of its version run on: [`Check::run_on`] takes from a [`Run`] the
/// function of this kind's version.
pub trait Checked: Loaded {
    /// The check function of `run` when it is a check of this version.
    fn check_fn(run: Run) -> Option<fn(&Self)>;

    /// Skips (by panicking with [`crate::outcome::skip`]'s payload) the check `name` where the
    /// FMU offers none of the interfaces it drives; called before every check.
    fn runnable(&self, _name: &str) {}
}

impl Checked for Fmu {
    fn check_fn(run: Run) -> Option<fn(&Self)> {
        match run {
            Run::Fmi2(f) => Some(f),
            Run::Fmi3(_) => None,
        }
    }
}

impl Checked for Fmu3 {
    fn check_fn(run: Run) -> Option<fn(&Self)> {
        match run {
            Run::Fmi3(f) => Some(f),
            Run::Fmi2(_) => None,
        }
    }

    fn runnable(&self, name: &str) {
        skip_unless_the_interfaces_allow(self, name);
    }
}

/// The checks that run on an FMU of Scheduled Execution only (as the Reference-FMUs' Clocks):
/// they drive no co-simulation or model-exchange instance.
const SCHEDULED_EXECUTION_CHECKS: [&str; 4] = [
    "fmi3_the_binary_exports_every_fmi3_function_and_no_others",
    "fmi3_get_version_is_3_0",
    "fmi3_instantiate_refuses_a_wrong_or_null_token_or_name_and_event_mode_with_null",
    "fmi3_scheduled_execution_activates_the_partitions_at_their_clocks_and_signals_the_clock_updates",
];

/// Skips the check `name` on an FMU that declares only `<ScheduledExecution>` unless it is one
/// of [`SCHEDULED_EXECUTION_CHECKS`]: the others drive a co-simulation or model-exchange instance,
/// which such an FMU does not offer (the reason names both declarations).
pub fn skip_unless_the_interfaces_allow(fmu: &Fmu3, name: &str) {
    if fmu.md.scheduled_execution_only() && !SCHEDULED_EXECUTION_CHECKS.contains(&name) {
        crate::outcome::skip_not_declared(
            "<CoSimulation> or <ModelExchange> (the FMU declares <ScheduledExecution> only; this check drives \
             co-simulation or model exchange)",
        );
    }
}
