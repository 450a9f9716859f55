//! Closed sets of named values (the walk form, the target language, the view, …): each
//! value's name as a command line writes it and a line of help, in one table per type
//! ([`Choice`]), so that front ends (the CLI, a host's own settings) offer them without
//! the library depending on any of them.

/// A type whose values are a closed set of named choices.
pub trait Choice: Copy + PartialEq + Send + Sync + 'static {
    /// Every value, with its name and a line of help.
    const CHOICES: &'static [(Self, &'static str, &'static str)];

    /// The value's name.
    fn name(self) -> &'static str {
        Self::CHOICES
            .iter()
            .find(|c| c.0 == self)
            .map_or("", |c| c.1)
    }

    /// The value of a name, if it is one.
    fn from_name(name: &str) -> Option<Self> {
        Self::CHOICES.iter().find(|c| c.1 == name).map(|c| c.0)
    }
}

/// Defines an enum whose variants are [`Choice`]s: `Variant = "name": "help",` each
/// (the help is also the variant's documentation), with `Display` by name.
macro_rules! choice_enum {
    (
        $(#[$meta:meta])*
        pub enum $name:ident {
            $( $(#[$vmeta:meta])* $variant:ident = $text:literal : $help:literal ),+ $(,)?
        }
    ) => {
        $(#[$meta])*
        pub enum $name {
            $( #[doc = $help] $(#[$vmeta])* $variant, )+
        }

        impl $crate::choice::Choice for $name {
            const CHOICES: &'static [($name, &'static str, &'static str)] =
                &[ $( ($name::$variant, $text, $help), )+ ];
        }

        impl std::fmt::Display for $name {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str($crate::choice::Choice::name(*self))
            }
        }
    };
}

pub(crate) use choice_enum;
