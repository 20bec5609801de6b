//! A non-finite `f32` (a NaN nodata) as a string in JSON.

use serde::{Deserialize, Deserializer, Serializer, de::Error as _};

pub(super) fn serialize<S: Serializer>(v: &f32, s: S) -> Result<S::Ok, S::Error> {
    if v.is_finite() {
        s.serialize_f32(*v)
    } else {
        s.serialize_str(&v.to_string())
    }
}

pub(super) fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f32, D::Error> {
    #[derive(Deserialize)]
    #[serde(untagged)]
    enum V {
        N(f32),
        S(String),
    }
    match V::deserialize(d)? {
        V::N(v) => Ok(v),
        V::S(s) => s.parse().map_err(D::Error::custom),
    }
}
