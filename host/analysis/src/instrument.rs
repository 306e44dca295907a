//! Who measured a data set, and so what its values are: the average over
//! which source and receiver apertures, at which wavelength. A value of this
//! head is carried from its own apertures to a standard's; a file from
//! another laboratory says nothing of its instrument unless its header or
//! the user does, and nothing is assumed for it.

use crate::coefficients::{head_apertures, Apertures, WAVELENGTH_NM};
use anyhow::{bail, Result};
use serde_json::{json, Value};

/// What measured a data set.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Instrument {
    /// This head: a collimated 633 nm laser and the detector's field
    /// (`calibrated.csv`, or a file `gonio convert` wrote from one).
    ThisHead,
    /// Another instrument whose apertures (angular diameters, degrees) and,
    /// if known, wavelength the user or the file's header stated.
    Stated { apertures: Apertures, wavelength_nm: Option<f64> },
    /// Nobody said: the values are left as they were measured.
    #[default]
    Unknown,
}

/// The header line (an ALTA comment) that states the instrument, as
/// `gonio convert` writes it and a laboratory may add to its own files:
/// `instrument source_aperture_deg=0 receiver_aperture_deg=0.39 wavelength_nm=633`.
pub const HEADER: &str = "instrument";
/// The header's word for this head's own data.
pub const THIS_HEAD: &str = "this_head";

impl Instrument {
    /// The apertures a measured value is the average over; `None` where
    /// unknown.
    pub fn apertures(&self) -> Option<Apertures> {
        match self {
            Instrument::ThisHead => Some(head_apertures()),
            Instrument::Stated { apertures, .. } => Some(*apertures),
            Instrument::Unknown => None,
        }
    }

    pub fn wavelength_nm(&self) -> Option<f64> {
        match self {
            Instrument::ThisHead => Some(WAVELENGTH_NM),
            Instrument::Stated { wavelength_nm, .. } => *wavelength_nm,
            Instrument::Unknown => None,
        }
    }

    /// Whether the head's own stage and arm uncertainties apply.
    pub fn is_this_head(&self) -> bool {
        *self == Instrument::ThisHead
    }

    /// What a measured value is the average over, in a clause.
    pub fn apertures_text(&self) -> String {
        match self {
            Instrument::ThisHead => {
                format!(
                    "the head's apertures (a collimated laser, a {:.2}° detector field)",
                    head_apertures().receiver_deg
                )
            }
            Instrument::Stated { apertures, .. } => format!(
                "the instrument's stated apertures (source {}°, receiver {}°)",
                apertures.source_deg, apertures.receiver_deg
            ),
            Instrument::Unknown => "an instrument whose apertures are not known (left as measured, not carried)".into(),
        }
    }

    /// The wavelength the values hold at, in a phrase.
    pub fn wavelength_text(&self) -> String {
        match self.wavelength_nm() {
            Some(nm) => format!("the instrument's wavelength ({nm} nm)"),
            None => "the instrument's wavelength, which the data do not state".into(),
        }
    }

    /// The header line's words after [`HEADER`] (this head's marked
    /// [`THIS_HEAD`], so that a converted file stays this head's).
    pub fn header_text(&self) -> Option<String> {
        let a = self.apertures()?;
        let mark = if self.is_this_head() {
            format!(" {THIS_HEAD}")
        } else {
            String::new()
        };
        let mut t = format!(
            "{HEADER}{mark} source_aperture_deg={} receiver_aperture_deg={}",
            a.source_deg, a.receiver_deg
        );
        if let Some(nm) = self.wavelength_nm() {
            t += &format!(" wavelength_nm={nm}");
        }
        Some(t)
    }

    /// The instrument a header line states (`None`: the line is not one,
    /// such as a laboratory's `# instrument Zeiss GK311`: every word of the
    /// header is `key=value` or [`THIS_HEAD`]).
    pub fn from_header(line: &str) -> Option<Result<Instrument>> {
        let rest = line.trim().strip_prefix(HEADER)?.strip_prefix(' ')?;
        if !rest.split_whitespace().all(|w| w.contains('=') || w == THIS_HEAD) {
            return None;
        }
        Some(Self::from_words(rest))
    }

    fn from_words(words: &str) -> Result<Instrument> {
        if words.split_whitespace().any(|w| w == THIS_HEAD) {
            return Ok(Instrument::ThisHead);
        }
        let (mut source, mut receiver, mut wavelength) = (None, None, None);
        for w in words.split_whitespace() {
            let Some((k, v)) = w.split_once('=') else {
                bail!("`{w}` is not key=value");
            };
            let v: f64 = match v.parse() {
                Ok(v) if f64::is_finite(v) && v >= 0.0 => v,
                _ => bail!("`{w}`: not a non-negative number"),
            };
            match k {
                "source_aperture_deg" => source = Some(v),
                "receiver_aperture_deg" => receiver = Some(v),
                "wavelength_nm" => wavelength = Some(v),
                _ => bail!("`{k}` is none of source_aperture_deg, receiver_aperture_deg, wavelength_nm"),
            }
        }
        Self::stated(source, receiver, wavelength)
    }

    /// An instrument the user states: both apertures are needed (what a
    /// value is the average over), the wavelength is optional; each a
    /// non-negative number.
    pub fn stated(source_deg: Option<f64>, receiver_deg: Option<f64>, wavelength_nm: Option<f64>) -> Result<Instrument> {
        if let Some(v) = [source_deg, receiver_deg, wavelength_nm]
            .into_iter()
            .flatten()
            .find(|v| !(v.is_finite() && *v >= 0.0))
        {
            bail!("an instrument's apertures and wavelength are non-negative numbers, not {v}");
        }
        match (source_deg, receiver_deg) {
            (Some(source_deg), Some(receiver_deg)) => Ok(Instrument::Stated {
                apertures: Apertures { source_deg, receiver_deg },
                wavelength_nm,
            }),
            (None, None) if wavelength_nm.is_none() => Ok(Instrument::Unknown),
            _ => bail!("an instrument is stated by both its source and receiver apertures (degrees), the wavelength optional"),
        }
    }

    pub fn to_json(&self) -> Value {
        match self {
            Instrument::ThisHead => json!({"name": "this head", "apertures": self.apertures(), "wavelength_nm": self.wavelength_nm()}),
            Instrument::Stated { apertures, wavelength_nm } => {
                json!({"name": "stated", "apertures": apertures, "wavelength_nm": wavelength_nm})
            }
            Instrument::Unknown => json!({"name": "unknown", "apertures": null, "wavelength_nm": null}),
        }
    }

    /// Read back; a file without it is of an instrument not known.
    pub fn from_json(v: &Value) -> Result<Instrument> {
        match v["name"].as_str() {
            Some("this head") => Ok(Instrument::ThisHead),
            Some("stated") => Self::stated(
                v["apertures"]["source_deg"].as_f64(),
                v["apertures"]["receiver_deg"].as_f64(),
                v["wavelength_nm"].as_f64(),
            ),
            Some("unknown") | None => Ok(Instrument::Unknown),
            Some(other) => bail!("instrument `{other}` is none of: this head, stated, unknown"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_header_line_round_trips_and_a_bad_one_is_named() {
        let i = Instrument::stated(Some(0.1), Some(0.2), Some(550.0)).unwrap();
        let line = i.header_text().unwrap();
        assert_eq!(Instrument::from_header(&line).unwrap().unwrap(), i);
        assert_eq!(
            Instrument::from_header(&Instrument::ThisHead.header_text().unwrap())
                .unwrap()
                .unwrap(),
            Instrument::ThisHead
        );
        assert!(Instrument::from_header("converted by gonio").is_none());
        assert!(Instrument::from_header("instrument Zeiss GK311").is_none());
        let e = Instrument::from_header("instrument source_aperture_deg=0.1").unwrap().unwrap_err();
        assert!(e.to_string().contains("both"), "{e}");
        assert!(Instrument::from_header("instrument colour=red").unwrap().is_err());
    }

    #[test]
    fn json_round_trips_and_absent_is_unknown() {
        for i in [
            Instrument::ThisHead,
            Instrument::Unknown,
            Instrument::stated(Some(0.0), Some(0.33), None).unwrap(),
        ] {
            assert_eq!(Instrument::from_json(&i.to_json()).unwrap(), i);
        }
        assert_eq!(Instrument::from_json(&Value::Null).unwrap(), Instrument::Unknown);
    }
}
