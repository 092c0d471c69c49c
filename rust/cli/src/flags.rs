//! Command-line flags built from the core's option tables
//! ([`sixaxis_core::request::train_options`], [`sixaxis_core::request::plan_options`]):
//! each option `key` is a flag `--key-with-dashes VALUE` (a bool: `--key` / `--no-key`), its
//! help is the option's doc line and default. The text is kept as given and parsed by the
//! core ([`sixaxis_core::options::Domain::parse_text`]), so a bad value gets the same error
//! as from Python or a request file.

use clap::{Arg, ArgAction, ArgMatches, Args, Command, FromArgMatches};
use sixaxis_core::generator::{generator_options, GeneratorOptions, GENERATOR_OPTIONS};
use sixaxis_core::options::{Domain, OptionInfo, OptionValue, Options};
use sixaxis_core::request::{plan_options, train_options};

/// The help text of an option: its doc line, its unit and where its default comes from
/// (a scenario field, or the value in `defaults`).
fn help(i: &OptionInfo, defaults: &[(&str, OptionValue)]) -> String {
    let mut h = i.doc_line();
    if !i.unit.is_empty() {
        h.push_str(&format!(" [{}]", i.unit));
    }
    if !i.field.is_empty() {
        h.push_str(&format!(" (default: the scenario's `{}`)", i.field));
    } else if let Some((_, v)) = defaults.iter().find(|(k, _)| *k == i.key) {
        h.push_str(&format!(" (default: {v})"));
    }
    h
}

fn value_name(d: &Domain) -> String {
    match d {
        Domain::Int { .. } => "N".into(),
        Domain::IntOrAuto { .. } => "N|auto".into(),
        Domain::Float { .. } => "X".into(),
        Domain::Bool => "BOOL".into(),
        Domain::Choice(names) => names.join("|"),
        Domain::Text => "TEXT".into(),
    }
}

fn off_id(key: &str) -> String {
    format!("no_{key}")
}

/// `cmd` with a flag for every option of `infos`.
fn add(mut cmd: Command, infos: &[OptionInfo], defaults: &[(&str, OptionValue)]) -> Command {
    for i in infos {
        let flag = i.flag();
        if i.domain == Domain::Bool {
            cmd = cmd
                .arg(
                    Arg::new(i.key)
                        .long(flag[2..].to_string())
                        .action(ArgAction::SetTrue)
                        .help(format!(
                            "{} On with this flag, off with `--no-{}`.",
                            help(i, defaults),
                            &flag[2..]
                        )),
                )
                .arg(
                    Arg::new(off_id(i.key))
                        .long(format!("no-{}", &flag[2..]))
                        .action(ArgAction::SetTrue)
                        .conflicts_with(i.key)
                        .help(format!("Turns `{flag}` off.")),
                );
        } else {
            cmd = cmd.arg(
                Arg::new(i.key)
                    .long(flag[2..].to_string())
                    .value_name(value_name(&i.domain))
                    .allow_hyphen_values(true)
                    .help(help(i, defaults)),
            );
        }
    }
    cmd
}

/// The options `m` holds, as text by key.
fn read(m: &ArgMatches, infos: &[OptionInfo]) -> Vec<(String, String)> {
    let mut given = Vec::new();
    for i in infos {
        if i.domain == Domain::Bool {
            if m.get_flag(i.key) {
                given.push((i.key.to_string(), "true".to_string()));
            } else if m.get_flag(&off_id(i.key)) {
                given.push((i.key.to_string(), "false".to_string()));
            }
        } else if let Some(t) = m.get_one::<String>(i.key) {
            given.push((i.key.to_string(), t.clone()));
        }
    }
    given
}

/// Flags as given, by key, before the core parses them.
fn parse(given: &[(String, String)], infos: &[OptionInfo]) -> sixaxis_core::Result<Options> {
    let mut out = Options::new();
    for (key, text) in given {
        let info = infos
            .iter()
            .find(|i| i.key == key)
            .expect("a flag of this table");
        out.insert(key.clone(), info.domain.parse_text(key, text)?);
    }
    Ok(out)
}

macro_rules! flag_set {
    ($(#[$m:meta])* $name:ident, $infos:expr, $defaults:expr) => {
        $(#[$m])*
        #[derive(Debug, Clone, Default)]
        pub struct $name(pub Vec<(String, String)>);

        impl $name {
            /// The options these flags give, parsed and checked by the core.
            pub fn options(&self) -> sixaxis_core::Result<Options> {
                parse(&self.0, &$infos)
            }
        }

        impl FromArgMatches for $name {
            fn from_arg_matches(m: &ArgMatches) -> Result<Self, clap::Error> {
                Ok($name(read(m, &$infos)))
            }
            fn update_from_arg_matches(&mut self, m: &ArgMatches) -> Result<(), clap::Error> {
                *self = Self::from_arg_matches(m)?;
                Ok(())
            }
        }

        impl Args for $name {
            fn augment_args(cmd: Command) -> Command {
                add(cmd, &$infos, &$defaults)
            }
            fn augment_args_for_update(cmd: Command) -> Command {
                add(cmd, &$infos, &$defaults)
            }
        }
    };
}

/// The options Algorithm 2 adds to training's.
fn plan_only() -> Vec<OptionInfo> {
    let train = train_options();
    plan_options()
        .into_iter()
        .filter(|p| !train.iter().any(|t| t.key == p.key))
        .collect()
}

flag_set!(
    /// The flags of a training run's options (`sixaxis train`, `sixaxis plan`).
    TrainFlags,
    train_options(),
    Vec::new()
);
flag_set!(
    /// The flags Algorithm 2 adds (`sixaxis plan`).
    PlanFlags,
    plan_only(),
    [("learner", OptionValue::Text("qlearning".into()))]
);
flag_set!(
    /// The flags of `sixaxis generate` (the options of the scenario generator).
    GeneratorFlags,
    generator_options(),
    GENERATOR_OPTIONS
        .iter()
        .map(|s| (s.info.key, (s.get)(&GeneratorOptions::default())))
        .collect::<Vec<_>>()
);
