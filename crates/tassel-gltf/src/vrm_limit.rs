//! Reading `VRMC_springBone_limit` (draft 1.0): a spring joint's cone, hinge or spherical
//! limit, from the `extensions` of a `VRMC_springBone` joint entry.

use glam::Quat;
use serde_json::Value;
use tassel::dynamics::vrm::{VrmLimit, VrmLimitShape};

/// The extension's name.
pub const EXTENSION: &str = "VRMC_springBone_limit";

/// The limit of joint entry `joint` (at `at` in messages), if it has one. An entry must hold
/// exactly one of `cone`, `hinge`, `spherical`; angles are radians and must be ≥ 0; a
/// `specVersion` other than "1.0-draft" (or "1.0") is read as the draft, with a warning.
pub(crate) fn read_limit(
    joint: &Value,
    at: &str,
    warnings: &mut Vec<String>,
) -> Result<Option<VrmLimit>, String> {
    let Some(ext) = joint.get("extensions").and_then(|e| e.get(EXTENSION)) else {
        return Ok(None);
    };
    let at = format!("{at}.extensions.{EXTENSION}");
    if !ext.is_object() {
        return Err(format!("{at} must be an object"));
    }
    match ext.get("specVersion").and_then(Value::as_str) {
        Some("1.0-draft") | Some("1.0") => {}
        Some(v) => warnings.push(format!(
            "{at}: specVersion '{v}' is not 1.0-draft; read as the 1.0 draft"
        )),
        None => warnings.push(format!(
            "{at}: no specVersion (required by the extension); read as the 1.0 draft"
        )),
    }
    let limit = ext.get("limit").filter(|l| l.is_object()).ok_or_else(|| {
        format!("{at}.limit is missing (an object with cone, hinge or spherical)")
    })?;
    let present: Vec<&str> = ["cone", "hinge", "spherical"]
        .into_iter()
        .filter(|k| limit.get(*k).is_some_and(|v| !v.is_null()))
        .collect();
    let kind = match present.as_slice() {
        [one] => *one,
        [] => return Err(format!("{at}.limit has none of cone, hinge, spherical")),
        more => {
            return Err(format!(
                "{at}.limit has {} ({}); the draft allows exactly one",
                more.len(),
                more.join(", ")
            ))
        }
    };
    let body = &limit[kind];
    let bat = format!("{at}.limit.{kind}");
    if !body.is_object() {
        return Err(format!("{bat} must be an object"));
    }
    let angle = |key: &str| -> Result<f32, String> {
        let v = body
            .get(key)
            .ok_or_else(|| format!("{bat}.{key} is missing (radians, required)"))?;
        let x = v
            .as_f64()
            .map(|x| x as f32)
            .filter(|x| x.is_finite())
            .ok_or_else(|| format!("{bat}.{key} must be a finite number, not {v}"))?;
        if x < 0.0 {
            return Err(format!(
                "{bat}.{key} is {x}; a limit angle must be ≥ 0 (radians)"
            ));
        }
        Ok(x)
    };
    let shape = match kind {
        "cone" => VrmLimitShape::Cone {
            angle: angle("angle")?,
        },
        "hinge" => VrmLimitShape::Hinge {
            angle: angle("angle")?,
        },
        _ => VrmLimitShape::Spherical {
            pitch: angle("pitch")?,
            yaw: angle("yaw")?,
        },
    };
    let rotation = match body.get("rotation") {
        None | Some(Value::Null) => Quat::IDENTITY,
        Some(Value::Array(a)) if a.len() == 4 => {
            let mut q = [0.0f32; 4];
            for (o, x) in q.iter_mut().zip(a) {
                *o = x
                    .as_f64()
                    .map(|x| x as f32)
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| format!("{bat}.rotation must be 4 finite numbers, not {x}"))?;
            }
            let q = Quat::from_array(q);
            if q.length_squared() < 1e-12 {
                return Err(format!(
                    "{bat}.rotation is zero; it must be a unit quaternion"
                ));
            }
            // As the file gives it: the solver normalises it when compiling.
            q
        }
        Some(other) => {
            return Err(format!(
                "{bat}.rotation must be 4 numbers (x, y, z, w), not {other}"
            ))
        }
    };
    Ok(Some(VrmLimit { shape, rotation }))
}
