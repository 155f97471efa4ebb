//! Illuminant files as `synth --illuminants` reads them: a camera-RGB part (gray-card
//! neutrals or a fitted Gaussian, [`super::parse_illuminants`]), an xy part (lamp
//! chromaticities in CIE 1931 xy, camera-independent) and the camera the file was measured
//! on. `calibrate illuminants` writes all three.
//!
//! The xy part (JSON, either form):
//!
//! ```json
//! {"format": "day2night-illuminants-xy/1",
//!  "observer": "CIE 1931 2 degree",
//!  "lamps": [{"name": "HP1", "weight": 10},
//!            {"name": "our car park", "xy": [0.5012, 0.4127], "weight": 2}]}
//! {"xy": [[0.5330, 0.4150], [0.44758, 0.40745]], "weights": [3, 1]}
//! ```
//!
//! A lamp without `xy` names a CIE 015:2018 lamp ([`super::cie_lamps::LAMPS`]); `weight`
//! (default 1) is a count of gray cards: the fit weighs each lamp by it, the unbiased
//! covariance divides by the total weight minus one. `observer`, when given, must be the CIE
//! 1931 2 degree observer. The camera (optional): `"camera": {"make": .., "model": ..,
//! "unique_camera_model": ..}`.

use super::{cie_lamps, parse_illuminants, IlluminantSource};
use crate::bounds::{self, MAX_DICT_ENTRIES, MAX_LAMP_WEIGHT};
use crate::error::{Error, Result};
use crate::raw::camera::CameraId;
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::path::Path;

/// Format tag of xy illuminant dictionaries (optional in files).
pub const XY_FORMAT: &str = "day2night-illuminants-xy/1";

/// A lamp of an xy dictionary.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct XyLamp {
    /// Name (a CIE name, the file's own, or `#i`).
    pub name: String,
    /// CIE 1931 xy, 2 degree observer.
    pub xy: [f64; 2],
    /// Weight (a count of gray cards).
    pub weight: f64,
}

/// A camera-independent illuminant dictionary in CIE 1931 xy.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct XyDict {
    /// Name used in messages (file path or the embedded name).
    pub name: String,
    /// Provenance / attribution.
    pub source: String,
    /// The lamps (weights > 0 are used).
    pub lamps: Vec<XyLamp>,
}

impl XyDict {
    /// The embedded CIE night lamps (the lamps of non-zero weight).
    pub fn cie_night() -> XyDict {
        XyDict {
            name: cie_lamps::NAME.into(),
            source: cie_lamps::ATTRIBUTION.into(),
            lamps: cie_lamps::night_lamps()
                .map(|l| XyLamp {
                    name: l.name.into(),
                    xy: l.xy,
                    weight: l.weight,
                })
                .collect(),
        }
    }
}

/// Everything an illuminant file holds.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct IlluminantFile {
    /// File path (messages, provenance).
    pub name: String,
    /// The camera the file was measured on, when it says.
    pub camera: Option<CameraId>,
    /// Camera-RGB part: neutrals or a Gaussian in the measuring camera's raw colours.
    pub rgb: Option<IlluminantSource>,
    /// xy part: camera-independent lamp chromaticities.
    pub xy: Option<XyDict>,
}

fn num(v: &Value, what: &str) -> Result<f64> {
    v.as_f64()
        .filter(|x| x.is_finite())
        .ok_or_else(|| Error::malformed(format!("{what}: {v} is not a finite number")))
}

fn xy_pair(v: &Value, what: &str) -> Result<[f64; 2]> {
    let xy = match v.as_array().map(|a| a.as_slice()) {
        Some([x, y]) => [num(x, what)?, num(y, what)?],
        _ => return Err(Error::malformed(format!("{what}: expected [x, y]"))),
    };
    bounds::chromaticity_xy(what, xy).map_err(bounds::malformed)?;
    Ok(xy)
}

fn weight(v: Option<&Value>, what: &str) -> Result<f64> {
    let w = match v {
        None => 1.0,
        Some(v) => num(v, what)?,
    };
    bounds::in_range(what, w, 0.0, MAX_LAMP_WEIGHT).map_err(bounds::malformed)?;
    Ok(w)
}

/// Parse the xy part of an illuminant file (`None` when it has none).
pub fn parse_xy(name: &str, v: &Value) -> Result<Option<XyDict>> {
    if let Some(obs) = v.get("observer") {
        let ok = obs.as_str().is_some_and(|s| {
            let s = s.to_ascii_lowercase();
            s.contains("1931") && s.contains('2')
        });
        if !ok {
            return Err(Error::malformed(format!(
                "observer {obs}: xy dictionaries are CIE 1931 2 degree chromaticities"
            )));
        }
    }
    let mut lamps = Vec::new();
    if let Some(list) = v.get("lamps") {
        let list = list
            .as_array()
            .ok_or_else(|| Error::malformed("lamps: not a list"))?;
        bounds::count("lamps", list.len(), MAX_DICT_ENTRIES)?;
        for (i, e) in list.iter().enumerate() {
            let what = format!("lamps[{i}]");
            let lname = e.get("name").and_then(|n| n.as_str());
            let xy = match (e.get("xy"), lname) {
                (Some(xy), _) => xy_pair(xy, &format!("{what}.xy"))?,
                (None, Some(n)) => {
                    cie_lamps::by_name(n)
                        .ok_or_else(|| {
                            Error::malformed(format!(
                                "{what}: {n:?} is not a CIE 015:2018 lamp (A, HP1-HP5, LED-B1..B5, \
                                 LED-BH1, LED-RGB1, LED-V1, LED-V2, FL1-FL12, FL3.1-FL3.15): \
                                 give its \"xy\""
                            ))
                        })?
                        .xy
                }
                (None, None) => {
                    return Err(Error::malformed(format!(
                        "{what}: needs \"xy\" or the \"name\" of a CIE lamp"
                    )))
                }
            };
            lamps.push(XyLamp {
                name: lname.map_or_else(|| format!("#{i}"), str::to_string),
                xy,
                weight: weight(e.get("weight"), &format!("{what}.weight"))?,
            });
        }
    } else if let Some(list) = v.get("xy") {
        let list = list
            .as_array()
            .ok_or_else(|| Error::malformed("xy: not a list"))?;
        bounds::count("xy", list.len(), MAX_DICT_ENTRIES)?;
        let weights = match v.get("weights") {
            None => None,
            Some(w) => {
                let w = w
                    .as_array()
                    .filter(|w| w.len() == list.len())
                    .ok_or_else(|| {
                        Error::malformed(format!(
                            "weights: expected a list of {} numbers (one per xy)",
                            list.len()
                        ))
                    })?;
                Some(w)
            }
        };
        for (i, e) in list.iter().enumerate() {
            lamps.push(XyLamp {
                name: format!("#{i}"),
                xy: xy_pair(e, &format!("xy[{i}]"))?,
                weight: weight(weights.and_then(|w| w.get(i)), &format!("weights[{i}]"))?,
            });
        }
    } else {
        return Ok(None);
    }
    if lamps.is_empty() {
        return Err(Error::malformed("xy dictionary: no lamps"));
    }
    if lamps.iter().all(|l| l.weight == 0.0) {
        return Err(Error::malformed("xy dictionary: every lamp has weight 0"));
    }
    let source = v
        .get("source")
        .and_then(|s| s.as_str())
        .unwrap_or("")
        .to_string();
    Ok(Some(XyDict {
        name: name.to_string(),
        source,
        lamps,
    }))
}

fn has_rgb(v: &Value) -> bool {
    [
        "illuminants_rgb_over_g",
        "illuminants",
        "chromaticities",
        "mean",
    ]
    .iter()
    .any(|k| v.get(k).is_some())
}

/// Parse an illuminant file: camera part, xy part, or both (module docs).
pub fn parse_illuminant_file(name: &str, v: &Value) -> Result<IlluminantFile> {
    if !v.is_object() {
        return Err(Error::malformed("an illuminant file is a JSON object"));
    }
    let camera = match v.get("camera") {
        None | Some(Value::Null) => None,
        Some(c) => {
            let id: CameraId = serde_json::from_value(c.clone()).map_err(|e| {
                Error::malformed(format!(
                    "camera: {e} (expected {{\"make\", \"model\", \"unique_camera_model\"}})"
                ))
            })?;
            let id = CameraId::new(id.make, id.model, id.unique_camera_model);
            (!id.is_unknown()).then_some(id)
        }
    };
    let xy = parse_xy(name, v)?;
    let rgb = if has_rgb(v) || xy.is_none() {
        Some(parse_illuminants(name, v)?)
    } else {
        None
    };
    Ok(IlluminantFile {
        name: name.to_string(),
        camera,
        rgb,
        xy,
    })
}

/// Read an illuminant file.
pub fn load_illuminant_file(path: &Path) -> Result<IlluminantFile> {
    let v = super::read_json(path)?;
    parse_illuminant_file(&path.display().to_string(), &v).map_err(|e| e.in_file(path))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(json: &str) -> Result<IlluminantFile> {
        parse_illuminant_file("f.json", &serde_json::from_str(json).unwrap())
    }

    #[test]
    fn both_xy_forms_and_cie_names() {
        let f = parse(
            r#"{"observer": "CIE 1931 2 degree", "lamps": [{"name": "hp1", "weight": 3},
                {"name": "mine", "xy": [0.45, 0.41]}]}"#,
        )
        .unwrap();
        assert!(f.rgb.is_none() && f.camera.is_none());
        let xy = f.xy.unwrap();
        assert_eq!(xy.lamps[0].xy, [0.5330, 0.4150]);
        assert_eq!((xy.lamps[0].weight, xy.lamps[1].weight), (3.0, 1.0));
        let f = parse(r#"{"xy": [[0.45, 0.41], [0.5, 0.4]], "weights": [2, 0]}"#).unwrap();
        let xy = f.xy.unwrap();
        assert_eq!(xy.lamps[1].weight, 0.0);
        assert_eq!(xy.lamps[1].name, "#1");
    }

    #[test]
    fn calibrate_files_carry_both_parts_and_the_camera() {
        let f = parse(
            r#"{"illuminants_rgb_over_g": [[0.5, 1, 0.3]], "xy": [[0.45, 0.41]],
                "camera": {"make": "Canon", "model": "EOS 5D", "unique_camera_model": null}}"#,
        )
        .unwrap();
        assert!(f.rgb.is_some() && f.xy.is_some());
        assert_eq!(f.camera.unwrap().label(), "Canon EOS 5D");
        // today's camera-RGB files are unchanged
        let f = parse(r#"{"illuminants": [[0.5, 0.3]]}"#).unwrap();
        assert!(f.rgb.is_some() && f.xy.is_none() && f.camera.is_none());
    }

    #[test]
    fn bad_xy_files_say_what_and_where() {
        let err = |j: &str| parse(j).unwrap_err().to_string();
        assert!(err(r#"{"xy": [[0.7, 0.35]]}"#).contains("xy[0]: x + y = 1.05"));
        assert!(err(r#"{"xy": [[0.4, 0.0]]}"#).contains("xy[0] y: 0 is outside"));
        assert!(err(r#"{"xy": [[0.4]]}"#).contains("xy[0]: expected [x, y]"));
        assert!(err(r#"{"xy": []}"#).contains("no lamps"));
        assert!(err(r#"{"xy": [[0.4, 0.4]], "weights": [0]}"#).contains("weight 0"));
        assert!(err(r#"{"xy": [[0.4, 0.4]], "weights": [1, 2]}"#).contains("one per xy"));
        assert!(err(r#"{"xy": [[0.4, 0.4]], "weights": [-1]}"#).contains("weights[0]"));
        assert!(err(r#"{"lamps": [{"name": "D65"}]}"#).contains("not a CIE 015:2018 lamp"));
        assert!(err(r#"{"lamps": [{"weight": 2}]}"#).contains("lamps[0]: needs"));
        assert!(err(r#"{"lamps": [{"xy": [0.4, "a"]}]}"#).contains("lamps[0].xy"));
        assert!(
            err(r#"{"observer": "CIE 1964 10 degree", "xy": [[0.4, 0.4]]}"#).contains("observer")
        );
        assert!(err(r#"{"camera": 3, "xy": [[0.4, 0.4]]}"#).contains("camera"));
        assert!(err(r#"[1, 2]"#).contains("JSON object"));
        assert!(err(r#"{}"#).contains("no illuminant list"));
    }
}
