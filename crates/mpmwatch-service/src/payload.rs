//! Decoding of what arrives on zenoh: the key expression `<prefix>/<controller>/<role>/<tag>` and
//! the JSON payload `{"t": <time>, "v": <number>}` or `{"t": [..], "v": [..]}` (DESIGN.md §4.3).
//! Pure functions: the ingest loop counts whatever they reject.

use serde_json::Value;

/// What a tag is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Role {
    /// Total manipulated variable.
    Mv,
    /// Dither added to an MV.
    Dither,
    /// Controlled variable.
    Cv,
    /// Model prediction of a CV.
    Pred,
}

impl Role {
    /// The key segment.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Mv => "mv",
            Self::Dither => "dither",
            Self::Cv => "cv",
            Self::Pred => "pred",
        }
    }

    fn parse(s: &str) -> Option<Self> {
        Some(match s {
            "mv" => Self::Mv,
            "dither" => Self::Dither,
            "cv" => Self::Cv,
            "pred" => Self::Pred,
            _ => return None,
        })
    }
}

/// A parsed input key.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct InputKey<'a> {
    /// Controller id.
    pub controller: &'a str,
    /// Role segment.
    pub role: Role,
    /// Tag.
    pub tag: &'a str,
}

/// Splits `<prefix>/<controller>/<role>/<tag>`; `None` for any other shape or an unknown role.
pub fn parse_key<'a>(prefix: &str, key: &'a str) -> Option<InputKey<'a>> {
    let rest = key.strip_prefix(prefix)?.strip_prefix('/')?;
    let mut it = rest.split('/');
    let (controller, role, tag) = (it.next()?, it.next()?, it.next()?);
    if it.next().is_some() || controller.is_empty() || tag.is_empty() {
        return None;
    }
    Some(InputKey { controller, role: Role::parse(role)?, tag })
}

/// Largest payload decoded, bytes: a message over it is refused before parsing, so one
/// publisher cannot make the service build a huge JSON tree (zenoh itself accepts up to 1 GiB).
pub const MAX_PAYLOAD_BYTES: usize = 16 << 20;

/// Most samples in one batch.
pub const MAX_BATCH: usize = 100_000;

/// A payload that cannot be decoded at all.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PayloadError {
    /// Not UTF-8 JSON.
    #[error("not JSON: {0}")]
    NotJson(String),
    /// JSON without the expected fields.
    #[error("expected {{\"t\": time, \"v\": number}} or {{\"t\": [..], \"v\": [..]}}: {0}")]
    Shape(String),
    /// A batch whose arrays differ in length.
    #[error("batch has {t} times and {v} values")]
    Lengths {
        /// Times.
        t: usize,
        /// Values.
        v: usize,
    },
    /// Over [`MAX_PAYLOAD_BYTES`] or [`MAX_BATCH`].
    #[error("payload too large: {0}")]
    TooLarge(String),
    /// A time that is neither a finite number of seconds nor RFC 3339.
    #[error("bad time {0}: seconds or RFC 3339 expected")]
    Time(String),
}

/// One decoded sample. `v` may be non-finite (`null`, `"NaN"`, `"inf"`): the caller counts it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Source time, seconds (RFC 3339 times become seconds since the Unix epoch).
    pub t: f64,
    /// Value.
    pub v: f64,
}

/// Decodes a single or batched payload. A bad time or value shape rejects the whole message, so
/// a batch never half-applies.
pub fn decode(bytes: &[u8]) -> Result<Vec<Sample>, PayloadError> {
    if bytes.len() > MAX_PAYLOAD_BYTES {
        return Err(PayloadError::TooLarge(format!("{} bytes, at most {MAX_PAYLOAD_BYTES}", bytes.len())));
    }
    let json: Value = serde_json::from_slice(bytes).map_err(|e| PayloadError::NotJson(e.to_string()))?;
    let obj = json.as_object().ok_or_else(|| PayloadError::Shape("not an object".into()))?;
    let t = obj.get("t").ok_or_else(|| PayloadError::Shape("no \"t\"".into()))?;
    let v = obj.get("v").ok_or_else(|| PayloadError::Shape("no \"v\"".into()))?;
    match (t, v) {
        (Value::Array(ts), Value::Array(vs)) => {
            if ts.len() != vs.len() {
                return Err(PayloadError::Lengths { t: ts.len(), v: vs.len() });
            }
            if ts.len() > MAX_BATCH {
                return Err(PayloadError::TooLarge(format!("{} samples, at most {MAX_BATCH}", ts.len())));
            }
            ts.iter().zip(vs).map(|(t, v)| Ok(Sample { t: time(t)?, v: value(v)? })).collect()
        }
        (Value::Array(_), _) | (_, Value::Array(_)) => {
            Err(PayloadError::Shape("\"t\" and \"v\" must both be arrays or both scalars".into()))
        }
        (t, v) => Ok(vec![Sample { t: time(t)?, v: value(v)? }]),
    }
}

fn time(t: &Value) -> Result<f64, PayloadError> {
    match t {
        Value::Number(n) => {
            n.as_f64().filter(|x| x.is_finite()).ok_or_else(|| PayloadError::Time(t.to_string()))
        }
        Value::String(s) => rfc3339(s).ok_or_else(|| PayloadError::Time(t.to_string())),
        _ => Err(PayloadError::Time(t.to_string())),
    }
}

/// Seconds since the Unix epoch of an RFC 3339 time, with its fraction.
pub fn rfc3339(s: &str) -> Option<f64> {
    let dt = chrono::DateTime::parse_from_rfc3339(s).ok()?;
    Some(dt.timestamp() as f64 + f64::from(dt.timestamp_subsec_nanos()) * 1e-9)
}

/// Numbers, `null` (missing, NaN) and the strings `"NaN"`, `"inf"`, `"-inf"` that historians
/// write for bad values (JSON has no literal for them). Anything else is a shape error.
fn value(v: &Value) -> Result<f64, PayloadError> {
    match v {
        Value::Number(n) => n.as_f64().ok_or_else(|| PayloadError::Shape(format!("value {v}"))),
        Value::Null => Ok(f64::NAN),
        Value::String(s) => match s.to_ascii_lowercase().as_str() {
            "nan" => Ok(f64::NAN),
            "inf" | "+inf" | "infinity" => Ok(f64::INFINITY),
            "-inf" | "-infinity" => Ok(f64::NEG_INFINITY),
            _ => s.parse::<f64>().map_err(|_| PayloadError::Shape(format!("value {v} is not a number"))),
        },
        _ => Err(PayloadError::Shape(format!("value {v} is not a number"))),
    }
}

/// The payload of one sample, as publishers (and the demo) write it.
pub fn encode(t: f64, v: f64) -> String {
    format!("{{\"t\":{t},\"v\":{v}}}")
}

/// A batch payload.
pub fn encode_batch(t: &[f64], v: &[f64]) -> String {
    serde_json::json!({"t": t, "v": v}).to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_split_into_controller_role_and_tag() {
        let k = parse_key("mpm", "mpm/c1/dither/ud1").unwrap();
        assert_eq!((k.controller, k.role, k.tag), ("c1", Role::Dither, "ud1"));
        assert!(parse_key("mpm", "mpm/c1/alarm").is_none());
        assert!(parse_key("mpm", "mpm/c1/xx/ud1").is_none());
        assert!(parse_key("mpm", "other/c1/mv/u1").is_none());
        assert!(parse_key("mpm", "mpm/c1/mv/u1/extra").is_none());
    }

    #[test]
    fn single_and_batch_payloads() {
        assert_eq!(decode(br#"{"t": 3.0, "v": 1.5}"#).unwrap(), vec![Sample { t: 3.0, v: 1.5 }]);
        let b = decode(br#"{"t": [1, 2], "v": [0.5, -0.5]}"#).unwrap();
        assert_eq!(b, vec![Sample { t: 1.0, v: 0.5 }, Sample { t: 2.0, v: -0.5 }]);
        let r = decode(br#"{"t": "1970-01-01T00:01:00.5Z", "v": 2}"#).unwrap();
        assert_eq!(r[0].t, 60.5);
        let o = decode(br#"{"t": "1970-01-01T01:00:00+01:00", "v": 2}"#).unwrap();
        assert_eq!(o[0].t, 0.0);
    }

    #[test]
    fn bad_values_decode_as_non_finite_and_bad_shapes_fail() {
        assert!(decode(br#"{"t": 1, "v": null}"#).unwrap()[0].v.is_nan());
        assert!(decode(br#"{"t": 1, "v": "NaN"}"#).unwrap()[0].v.is_nan());
        assert_eq!(decode(br#"{"t": 1, "v": "-inf"}"#).unwrap()[0].v, f64::NEG_INFINITY);
        assert!(matches!(decode(b"not json"), Err(PayloadError::NotJson(_))));
        assert!(matches!(decode(br#"{"v": 1}"#), Err(PayloadError::Shape(_))));
        assert!(matches!(decode(br#"{"t": [1], "v": [1, 2]}"#), Err(PayloadError::Lengths { .. })));
        assert!(matches!(decode(br#"{"t": "yesterday", "v": 1}"#), Err(PayloadError::Time(_))));
        assert!(matches!(decode(br#"{"t": [1], "v": 1}"#), Err(PayloadError::Shape(_))));
        assert!(matches!(decode(br#"{"t": 1, "v": {}}"#), Err(PayloadError::Shape(_))));
    }

    #[test]
    fn oversized_payloads_and_batches_are_refused() {
        let big = vec![b' '; MAX_PAYLOAD_BYTES + 1];
        assert!(matches!(decode(&big), Err(PayloadError::TooLarge(_))));
        let n = MAX_BATCH + 1;
        let batch = encode_batch(&vec![1.0; n], &vec![0.0; n]);
        assert!(matches!(decode(batch.as_bytes()), Err(PayloadError::TooLarge(_))));
    }

    #[test]
    fn encoded_payloads_decode() {
        assert_eq!(decode(encode(2.5, -1.0).as_bytes()).unwrap(), vec![Sample { t: 2.5, v: -1.0 }]);
        assert_eq!(decode(encode_batch(&[1.0], &[2.0]).as_bytes()).unwrap().len(), 1);
    }
}
