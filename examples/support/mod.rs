//! Command-line parsing shared by the headless examples: `--key value` pairs and bare flags,
//! with unknown flags and bad values reported as errors.

#![allow(dead_code, reason = "each example uses a different part of it")]

use std::collections::HashMap;
use std::str::FromStr;

/// Parsed `--key value` options and `--flag`s.
pub struct Args {
    values: HashMap<String, String>,
    flags: Vec<String>,
}

impl Args {
    /// Parses `std::env::args()`: `valued` names take a value, `flags` do not.
    pub fn parse(valued: &[&str], flags: &[&str]) -> Result<Self, String> {
        let mut values = HashMap::new();
        let mut seen_flags = Vec::new();
        let mut args = std::env::args().skip(1);
        while let Some(arg) = args.next() {
            let Some(name) = arg.strip_prefix("--") else {
                return Err(format!("unexpected argument '{arg}'"));
            };
            if name == "help" {
                return Err(HELP.to_string());
            }
            if flags.contains(&name) {
                seen_flags.push(name.to_string());
            } else if valued.contains(&name) {
                let value = args
                    .next()
                    .ok_or_else(|| format!("--{name} needs a value"))?;
                values.insert(name.to_string(), value);
            } else {
                return Err(format!("unknown option '--{name}'"));
            }
        }
        Ok(Self {
            values,
            flags: seen_flags,
        })
    }

    /// Whether `--name` was given.
    pub fn flag(&self, name: &str) -> bool {
        self.flags.iter().any(|f| f == name)
    }

    /// The raw value of `--name`, if given.
    pub fn text(&self, name: &str) -> Option<&str> {
        self.values.get(name).map(String::as_str)
    }

    /// `--name` parsed, or `default`.
    pub fn get<T: FromStr>(&self, name: &str, default: T) -> Result<T, String> {
        match self.values.get(name) {
            None => Ok(default),
            Some(text) => text
                .parse()
                .map_err(|_| format!("--{name}: cannot read '{text}' as a number")),
        }
    }

    /// `--name` parsed as a finite positive number, or `default`.
    pub fn positive(&self, name: &str, default: f32) -> Result<f32, String> {
        let value: f32 = self.get(name, default)?;
        if value.is_finite() && value > 0.0 {
            Ok(value)
        } else {
            Err(format!("--{name} must be a positive number, got {value}"))
        }
    }
}

/// What [`Args::parse`] returns for `--help`.
const HELP: &str = "help";

/// Prints the usage and exits: with status 0 for `--help`, otherwise with `error` on stderr and
/// status 2.
pub fn fail(error: &str, usage: &str) -> ! {
    if error == HELP {
        println!("{usage}");
        std::process::exit(0);
    }
    eprintln!("error: {error}\n");
    eprintln!("{usage}");
    std::process::exit(2);
}
