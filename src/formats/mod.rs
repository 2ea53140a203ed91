//! The application's file formats: the bench's JSON input, `vrao render`'s still images
//! and the PNG and JSON writers.

pub mod bench_file;
pub mod output;
pub mod spans;
pub mod still;

/// Serde for a setting chosen by name ([`Choice`](vrao_ao::Choice)): written as its name, read from its
/// name or an alias, an unknown name refused with the accepted ones
/// (`#[serde(with = "crate::formats::by_name")]`).
pub mod by_name {
    use serde::{de::Error as _, Deserialize, Deserializer, Serializer};
    use vrao_ao::Choice;

    /// Writes the value's name.
    pub fn serialize<T: Choice, S: Serializer>(value: &T, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.serialize_str(value.name())
    }

    /// Reads a name.
    pub fn deserialize<'de, T: Choice, D: Deserializer<'de>>(deserializer: D) -> Result<T, D::Error> {
        let name = String::deserialize(deserializer)?;
        T::from_name(&name).ok_or_else(|| {
            let names: Vec<&str> = T::all().iter().map(|v| v.name()).collect();
            D::Error::custom(format!("unknown variant `{name}`, expected one of {}", names.join(", ")))
        })
    }
}
