//! IMU samples one text line at a time, for live input (stdin, UDP): either
//! the gyro CSV (a header line `t,wx,wy,wz[,vx,vy,vz][,depth]`, then one
//! sample per line) or JSON lines (`{"t": .., "wx": .., "wy": .., "wz": ..}`,
//! optional `vx, vy, vz, depth`). Lines starting with `#` and blank lines are
//! skipped. Units and the IMU-to-camera rotation are [`GyroOptions`]'s.
//!
//! Each line is parsed on its own: a bad line is an error naming its line
//! number and leaves the parser ready for the next one.

use super::gyro::{GyroOptions, GyroSample};
use crate::error::{quote, Error, Result};
use glam::DVec3;

/// Column positions of a CSV header.
#[derive(Debug, Clone)]
struct Columns {
    t: usize,
    w: [usize; 3],
    v: Option<[usize; 3]>,
    depth: Option<usize>,
    count: usize,
}

/// Parses sample lines (see the module docs).
#[derive(Debug, Clone)]
pub struct LineParser {
    opts: GyroOptions,
    source: String,
    columns: Option<Columns>,
}

impl LineParser {
    /// A parser for lines from `source` (named in errors, e.g. `<stdin>`).
    pub fn new(opts: GyroOptions, source: &str) -> Self {
        LineParser {
            opts,
            source: source.to_string(),
            columns: None,
        }
    }

    fn err(&self, line: u64, column: &str, message: String) -> Error {
        Error::Parse {
            path: self.source.clone().into(),
            line,
            column: column.to_string(),
            message,
        }
    }

    /// Parses line number `line` (1-based): `Ok(None)` for a header, a
    /// comment or a blank line, `Ok(Some(sample))` for a sample.
    pub fn parse(&mut self, text: &str, line: u64) -> Result<Option<GyroSample>> {
        let text = text.trim();
        if text.is_empty() || text.starts_with('#') {
            return Ok(None);
        }
        if text.starts_with('{') {
            return self.json(text, line).map(Some);
        }
        match self.columns.clone() {
            None => {
                self.columns = Some(self.header(text, line)?);
                Ok(None)
            }
            Some(c) => self.csv(text, line, &c).map(Some),
        }
    }

    fn header(&self, text: &str, line: u64) -> Result<Columns> {
        let names: Vec<&str> = text.split(',').map(str::trim).collect();
        for n in ["t", "wx", "wy", "wz", "vx", "vy", "vz", "depth"] {
            if names.iter().filter(|h| **h == n).count() > 1 {
                return Err(self.err(line, n, format!("column '{n}' appears more than once")));
            }
        }
        let find = |n: &str| names.iter().position(|h| *h == n);
        let need = |n: &str| {
            find(n).ok_or_else(|| {
                self.err(
                    line,
                    n,
                    format!(
                        "expected a header with t,wx,wy,wz (or JSON lines); got {}",
                        quote(text)
                    ),
                )
            })
        };
        let v = match (find("vx"), find("vy"), find("vz")) {
            (Some(a), Some(b), Some(c)) => Some([a, b, c]),
            (None, None, None) => None,
            _ => {
                return Err(self.err(
                    line,
                    "vx,vy,vz",
                    "velocity columns must come as all three of vx, vy, vz".into(),
                ))
            }
        };
        Ok(Columns {
            t: need("t")?,
            w: [need("wx")?, need("wy")?, need("wz")?],
            v,
            depth: find("depth"),
            count: names.len(),
        })
    }

    fn number(&self, s: &str, line: u64, column: &str) -> Result<f64> {
        let x: f64 = s
            .trim()
            .parse()
            .map_err(|_| self.err(line, column, format!("{} is not a number", quote(s))))?;
        if !x.is_finite() {
            return Err(self.err(line, column, format!("{} is not finite", quote(s))));
        }
        Ok(x)
    }

    fn csv(&self, text: &str, line: u64, c: &Columns) -> Result<GyroSample> {
        let f: Vec<&str> = text.split(',').collect();
        if f.len() != c.count {
            return Err(self.err(
                line,
                "-",
                format!("{} fields, the header has {}", f.len(), c.count),
            ));
        }
        let num = |i: usize, name: &str| self.number(f[i], line, name);
        let w = DVec3::new(num(c.w[0], "wx")?, num(c.w[1], "wy")?, num(c.w[2], "wz")?);
        let v = match c.v {
            Some(i) => Some(DVec3::new(
                num(i[0], "vx")?,
                num(i[1], "vy")?,
                num(i[2], "vz")?,
            )),
            None => None,
        };
        let depth = match c.depth {
            Some(i) => Some(num(i, "depth")?),
            None => None,
        };
        Ok(self.opts.sample(num(c.t, "t")?, w, v, depth))
    }

    fn json(&self, text: &str, line: u64) -> Result<GyroSample> {
        let obj: serde_json::Map<String, serde_json::Value> = serde_json::from_str(text)
            .map_err(|e| self.err(line, "-", format!("not a JSON object: {e}")))?;
        let get = |k: &str| -> Result<Option<f64>> {
            match obj.get(k) {
                None | Some(serde_json::Value::Null) => Ok(None),
                Some(v) => match v.as_f64() {
                    Some(x) if x.is_finite() => Ok(Some(x)),
                    _ => Err(self.err(
                        line,
                        k,
                        format!("{} is not a finite number", quote(&v.to_string())),
                    )),
                },
            }
        };
        let need = |k: &str| get(k)?.ok_or_else(|| self.err(line, k, format!("missing \"{k}\"")));
        let w = DVec3::new(need("wx")?, need("wy")?, need("wz")?);
        let v = match (get("vx")?, get("vy")?, get("vz")?) {
            (Some(a), Some(b), Some(c)) => Some(DVec3::new(a, b, c)),
            (None, None, None) => None,
            _ => {
                return Err(self.err(
                    line,
                    "vx,vy,vz",
                    "velocity must come as all three of vx, vy, vz".into(),
                ))
            }
        };
        Ok(self.opts.sample(need("t")?, w, v, get("depth")?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_and_json_lines() {
        let mut p = LineParser::new(GyroOptions::default(), "<test>");
        assert!(p.parse("# comment", 1).unwrap().is_none());
        assert!(p.parse("t,wx,wy,wz", 2).unwrap().is_none());
        let s = p.parse("0.5,1,2,3", 3).unwrap().unwrap();
        assert_eq!((s.t, s.omega), (0.5, DVec3::new(1.0, 2.0, 3.0)));
        let e = p.parse("0.6,1,x,3", 4).unwrap_err().to_string();
        assert!(e.contains("<test>:4:wy") && e.contains("'x'"), "{e}");
        // Still usable after a bad line.
        assert!(p.parse("0.7,1,2,3", 5).unwrap().is_some());
        let s = p
            .parse(r#"{"t": 1.0, "wx": 0.1, "wy": 0, "wz": -0.2}"#, 6)
            .unwrap()
            .unwrap();
        assert_eq!(s.omega, DVec3::new(0.1, 0.0, -0.2));
        assert!(p.parse(r#"{"t": 1.0, "wx": 0.1}"#, 7).is_err());
        assert!(p.parse("{not json", 8).is_err());
        assert!(p.parse("1,2", 9).is_err());
    }

    #[test]
    fn units_as_the_file_reader() {
        let opts = GyroOptions {
            time_unit: crate::io::gyro::TimeUnit::Ms,
            angle_unit: crate::io::gyro::AngleUnit::Deg,
            ..GyroOptions::default()
        };
        let mut p = LineParser::new(opts, "<test>");
        p.parse("t,wx,wy,wz", 1).unwrap();
        let s = p.parse("1500,180,0,0", 2).unwrap().unwrap();
        assert!((s.t - 1.5).abs() < 1e-15);
        assert!((s.omega.x - std::f64::consts::PI).abs() < 1e-15);
    }
}
