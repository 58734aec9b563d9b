//! Which robots a run logs, and how often: the scenario's `[log] robots`
//! and each robot's `log` (`log = false`, `[robots.log] rate_hz`), with the
//! command line's `--log-robots` and `--log-rate [PATTERN=]RATE` over them.
//! A herd of hundreds is then logged as a few robots at full rate, the rest
//! decimated or not at all (docs/logs.md, "Which robots, how often").

use bevy_ecs::entity::Entity;

use crate::scenario::Scenario;
use crate::scenario::format::LogRateSpec;
use crate::world::World;

pub use crate::names::RobotPattern;

/// The command line's say over the log (`quadsim run`).
#[derive(Debug, Clone, Default)]
pub struct LogOverrides {
    /// `--log-robots`: the robots logged, replacing `[log] robots` and every
    /// robot's `log` setting.
    pub robots: Option<Vec<RobotPattern>>,
    /// `--log-rate PATTERN=RATE`: decimation (steps) of the matching robots,
    /// over their `[robots.log] rate_hz`; a later match wins.
    pub rates: Vec<(RobotPattern, u64)>,
}

impl LogOverrides {
    /// Parses `--log-robots NAME,PATTERN,...`.
    pub fn parse_robots(list: &str) -> Result<Vec<RobotPattern>, String> {
        list.split(',')
            .map(|p| RobotPattern::new(p.trim()))
            .collect()
    }

    /// Checks that every pattern matches a robot of `names`.
    pub fn check_matches<'a>(
        &self,
        names: impl Iterator<Item = &'a str> + Clone,
    ) -> Result<(), String> {
        let patterns = self
            .robots
            .iter()
            .flatten()
            .map(|p| ("--log-robots", p))
            .chain(self.rates.iter().map(|(p, _)| ("--log-rate", p)));
        for (flag, p) in patterns {
            if !names.clone().any(|n| p.matches(n)) {
                return Err(format!("{flag}: '{}' matches no robot", p.as_str()));
            }
        }
        Ok(())
    }
}

/// Splits one `--log-rate` value into an optional robot pattern and a rate:
/// `50`, `full`, `q16-*=10`, `rex=full`.
pub fn parse_rate_arg(arg: &str) -> Result<(Option<RobotPattern>, LogRateSpec), String> {
    let (pattern, rate) = match arg.rsplit_once('=') {
        Some((p, r)) => (Some(RobotPattern::new(p.trim())?), r.trim()),
        None => (None, arg.trim()),
    };
    let spec = match rate.parse::<f64>() {
        Ok(hz) => LogRateSpec::Hz(hz),
        Err(_) => LogRateSpec::Named(rate.to_string()),
    };
    Ok((pattern, spec))
}

/// Each robot's decimation in a run's log.
#[derive(Debug, Clone, PartialEq)]
pub struct LogPlan {
    /// The world's log decimation (steps), recorded as `log_every_steps`:
    /// robots without a rate of their own are sampled this often.
    pub every_steps: u64,
    /// Every robot of the world in its order: root entity, name, and steps
    /// between its samples (`None`: no per-step channels).
    pub robots: Vec<(Entity, String, Option<u64>)>,
}

impl LogPlan {
    /// The plan of `scn` for `world` at the world decimation `every_steps`,
    /// with the command line's `overrides`. The scenario's rates and patterns
    /// were validated on load; a robot rate that does not fit `dt` (only
    /// possible for robots built outside the scenario) falls back to the world's.
    pub fn new(scn: &Scenario, world: &World, every_steps: u64, o: &LogOverrides) -> Self {
        let file = &scn.file;
        let robots = world
            .robots
            .iter()
            .map(|(name, e)| {
                let spec = file.robots.iter().find(|r| &r.name == name);
                let selected = match &o.robots {
                    Some(ps) => ps.iter().any(|p| p.matches(name)),
                    None => {
                        spec.is_none_or(|r| r.log.enabled)
                            && file.log.robots.as_ref().is_none_or(|ps| {
                                ps.iter()
                                    .any(|p| RobotPattern::new(p).is_ok_and(|p| p.matches(name)))
                            })
                    }
                };
                let own = spec
                    .and_then(|r| r.log.rate_hz.as_ref())
                    .and_then(|r| r.every_steps(world.dt_s).ok());
                let cli = o
                    .rates
                    .iter()
                    .rev()
                    .find(|(p, _)| p.matches(name))
                    .map(|&(_, d)| d);
                let every = cli.or(own).unwrap_or(every_steps).max(1);
                (*e, name.clone(), selected.then_some(every))
            })
            .collect();
        Self {
            every_steps: every_steps.max(1),
            robots,
        }
    }

    /// Every robot at the world's rate (no robot off, none at its own rate).
    pub fn is_uniform(&self) -> bool {
        self.robots
            .iter()
            .all(|(_, _, d)| *d == Some(self.every_steps))
    }

    /// Robots with per-step channels.
    pub fn logged(&self) -> usize {
        self.robots.iter().filter(|(_, _, d)| d.is_some()).count()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn patterns_match_names_and_globs() {
        let p = RobotPattern::new("q16-00*").unwrap();
        assert!(p.matches("q16-000") && p.matches("q16-009"));
        assert!(!p.matches("q16-010") && !p.matches("q12-000"));
        assert!(RobotPattern::new("rex").unwrap().matches("rex"));
        assert!(!RobotPattern::new("rex").unwrap().matches("rex2"));
        assert!(RobotPattern::new("q1[26]-0?1").unwrap().matches("q12-031"));
        assert!(RobotPattern::new("").is_err());
        assert!(RobotPattern::new("a[").is_err());
    }

    #[test]
    fn rate_arguments_split_at_the_last_equals_sign() {
        let (p, r) = parse_rate_arg("50").unwrap();
        assert!(p.is_none());
        assert_eq!(r, LogRateSpec::Hz(50.0));
        let (p, r) = parse_rate_arg("q16-*=full").unwrap();
        assert_eq!(p.unwrap().as_str(), "q16-*");
        assert_eq!(r, LogRateSpec::Named("full".into()));
        assert!(parse_rate_arg("=10").is_err());
    }
}
