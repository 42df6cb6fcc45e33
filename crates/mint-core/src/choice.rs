//! Closed sets of named values ("choices"): the sign rule, the boolean
//! operator, the slab axis, a stage of the engine. Each is declared once
//! with [`choice!`](crate::choice!), which gives it its names, its
//! (de)serialization by those names, and the list the command line offers,
//! so that a value's spelling has one owner from `--help` to `plan.json`.
//! An unknown name is an error that lists the known ones, never a default.

#[doc(hidden)]
pub use serde as __serde;

/// A value of a closed set with one name per value.
pub trait Choice: Copy + PartialEq + Send + Sync + 'static {
    /// Every value, in the order `--help` lists them.
    const ALL: &'static [Self];
    /// Their names, in the same order.
    const NAMES: &'static [&'static str];
    /// This value's name.
    fn name(self) -> &'static str;
    /// The value named `s`, or an error listing the names.
    fn parse(s: &str) -> Result<Self, String> {
        Self::NAMES.iter().position(|n| *n == s).map(|i| Self::ALL[i]).ok_or_else(|| format!("unknown value '{s}' (expected one of: {})", Self::NAMES.join(", ")))
    }
}

/// Declares a [`Choice`] enum: `choice! { pub enum X { A => "a", B => "b" } }`.
/// Derives `Debug, Clone, Copy, PartialEq, Eq, Hash`; implements
/// `Display` and serde's traits by name.
#[macro_export]
macro_rules! choice {
    ($(#[$m:meta])* $vis:vis enum $name:ident { $($(#[$vm:meta])* $var:ident => $s:literal),+ $(,)? }) => {
        $(#[$m])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
        $vis enum $name { $($(#[$vm])* $var),+ }
        impl $crate::choice::Choice for $name {
            const ALL: &'static [Self] = &[$($name::$var),+];
            const NAMES: &'static [&'static str] = &[$($s),+];
            fn name(self) -> &'static str {
                match self { $($name::$var => $s),+ }
            }
        }
        impl ::std::fmt::Display for $name {
            fn fmt(&self, f: &mut ::std::fmt::Formatter<'_>) -> ::std::fmt::Result {
                f.pad($crate::choice::Choice::name(*self))
            }
        }
        impl $crate::choice::__serde::Serialize for $name {
            fn serialize<S: $crate::choice::__serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                s.serialize_str($crate::choice::Choice::name(*self))
            }
        }
        impl<'de> $crate::choice::__serde::Deserialize<'de> for $name {
            fn deserialize<D: $crate::choice::__serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                let s = <::std::borrow::Cow<'de, str> as $crate::choice::__serde::Deserialize>::deserialize(d)?;
                <Self as $crate::choice::Choice>::parse(&s).map_err(<D::Error as $crate::choice::__serde::de::Error>::custom)
            }
        }
    };
}

#[cfg(test)]
mod tests {
    use super::Choice;

    crate::choice! {
        /// A test set.
        enum Fruit { Apple => "apple", Pear => "pear" }
    }

    #[test]
    fn names_round_trip_and_unknown_names_are_listed() {
        for &f in Fruit::ALL {
            assert_eq!(Fruit::parse(f.name()), Ok(f));
            assert_eq!(f.to_string(), f.name());
        }
        assert_eq!(Fruit::parse("plum").unwrap_err(), "unknown value 'plum' (expected one of: apple, pear)");
    }
}
