//! Opaque, stable ids. `J12` and `R34` are what users type; the number has no meaning beyond identity, and where a
//! junction or road came from is kept in its [`crate::Provenance`], not in the id.

use serde::{Deserialize, Deserializer, Serialize, Serializer};
use std::fmt;
use std::str::FromStr;

macro_rules! opaque_id {
    ($name:ident, $prefix:literal, $what:literal) => {
        #[doc = concat!("Opaque id of a ", $what, ", written `", $prefix, "<n>`.")]
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub struct $name(pub u32);

        impl fmt::Display for $name {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                write!(f, concat!($prefix, "{}"), self.0)
            }
        }

        impl FromStr for $name {
            type Err = String;
            fn from_str(s: &str) -> Result<Self, String> {
                s.strip_prefix($prefix)
                    .and_then(|n| n.parse::<u32>().ok())
                    .map($name)
                    .ok_or_else(|| {
                        format!(
                            concat!(
                                "`{}` is not a ",
                                $what,
                                " id (expected ",
                                $prefix,
                                "<number>)"
                            ),
                            s
                        )
                    })
            }
        }

        impl Serialize for $name {
            fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                s.collect_str(self)
            }
        }

        impl<'de> Deserialize<'de> for $name {
            fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                let s = String::deserialize(d)?;
                s.parse().map_err(serde::de::Error::custom)
            }
        }
    };
}

opaque_id!(JunctionId, "J", "junction");
opaque_id!(RoadId, "R", "road");

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_round_trip_through_text() {
        assert_eq!("J12".parse::<JunctionId>().unwrap(), JunctionId(12));
        assert_eq!(RoadId(34).to_string(), "R34");
        assert!("R12".parse::<JunctionId>().is_err());
        assert!("J".parse::<JunctionId>().is_err());
        assert!("J-1".parse::<JunctionId>().is_err());
        let json = serde_json::to_string(&RoadId(7)).unwrap();
        assert_eq!(json, "\"R7\"");
        assert_eq!(serde_json::from_str::<RoadId>(&json).unwrap(), RoadId(7));
    }
}
