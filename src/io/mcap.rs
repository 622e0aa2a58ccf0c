//! ROS 2 logs: `sensor_msgs/msg/Imu` messages from an MCAP file (rosbag2's
//! default storage format), decoded from CDR.
//!
//! - Time: the message's `header.stamp` (`sec + nanosec / 1e9`, s; the
//!   measurement time set by the driver); a message whose stamp is zero
//!   takes its MCAP log time instead.
//! - Angular velocity: `angular_velocity` in rad/s, in the message's
//!   `header.frame_id` frame (ROS REP 103/145). The IMU-to-camera rotation
//!   is the log options' `imu_to_camera` (`--imu-rotation`), as for CSV logs;
//!   mmbm does not read `/tf`.
//! - Topic: the one asked for, or the only topic with `sensor_msgs/msg/Imu`
//!   messages; any other message is ignored.
//!
//! The whole file is read into memory (chunks are decompressed one at a
//! time): keep IMU-only bags, or split off the IMU topic with
//! `ros2 bag convert`, for logs far larger than the machine's memory.

use crate::error::{Error, Result};
use glam::DVec3;
use std::collections::BTreeMap;
use std::path::Path;

/// The ROS 2 type name of the messages read.
pub const IMU_SCHEMA: &str = "sensor_msgs/msg/Imu";

/// The first bytes of every MCAP file.
const MAGIC: &[u8] = b"\x89MCAP0\r\n";

/// One decoded IMU message.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImuMessage {
    /// Header stamp (or log time), s.
    pub t: f64,
    /// Angular velocity, rad/s, IMU frame.
    pub omega: DVec3,
}

/// True when `path` names an MCAP file (by extension, or by its first bytes).
pub fn is_mcap(path: &Path) -> bool {
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("mcap"))
    {
        return true;
    }
    // Only a regular file is sniffed (reading a pipe would consume it).
    if !super::input::is_regular_file(path) {
        return false;
    }
    let mut head = [0u8; 8];
    std::fs::File::open(path)
        .and_then(|mut f| std::io::Read::read_exact(&mut f, &mut head))
        .is_ok_and(|_| head == MAGIC)
}

/// Reads the IMU messages of `topic` (None: the only IMU topic) from the
/// MCAP file at `path`, in file order.
pub fn read_imu(path: &Path, topic: Option<&str>) -> Result<Vec<ImuMessage>> {
    // A whole-file read: a regular file only (never a device or a pipe).
    let mut bytes = Vec::new();
    std::io::Read::read_to_end(&mut super::input::open_file(path)?, &mut bytes)
        .map_err(|e| Error::io(path, e))?;
    let bad = |what: String| Error::invalid(path.display().to_string(), what);
    // Which topics carry IMU messages (read from the messages themselves:
    // the summary section is optional).
    let mut topics: BTreeMap<String, usize> = BTreeMap::new();
    let stream = ::mcap::MessageStream::new(&bytes)
        .map_err(|e| bad(format!("not a readable MCAP file: {e}")))?;
    let mut messages = Vec::new();
    for (k, m) in stream.enumerate() {
        let m = m.map_err(|e| bad(format!("MCAP record near message {}: {e}", k + 1)))?;
        let ch = &m.channel;
        let is_imu = ch.schema.as_ref().is_some_and(|s| s.name == IMU_SCHEMA);
        if !is_imu {
            continue;
        }
        *topics.entry(ch.topic.clone()).or_default() += 1;
        if ch.message_encoding != "cdr" {
            return Err(bad(format!(
                "topic {}: message encoding '{}', expected 'cdr'",
                ch.topic, ch.message_encoding
            )));
        }
        messages.push((ch.topic.clone(), m.log_time, m.data.into_owned()));
    }
    let list = || {
        if topics.is_empty() {
            "none".to_string()
        } else {
            topics
                .iter()
                .map(|(t, n)| format!("{t} ({n} messages)"))
                .collect::<Vec<_>>()
                .join(", ")
        }
    };
    let chosen = match topic {
        Some(t) if topics.contains_key(t) => t.to_string(),
        Some(t) => {
            return Err(bad(format!(
                "no {IMU_SCHEMA} messages on topic '{t}'; IMU topics: {}",
                list()
            )))
        }
        None if topics.len() == 1 => topics.keys().next().cloned().unwrap_or_default(),
        None => {
            return Err(bad(format!(
                "choose an IMU topic with --topic; IMU topics: {}",
                list()
            )))
        }
    };
    let mut out = Vec::new();
    for (t, log_time, data) in &messages {
        if *t != chosen {
            continue;
        }
        let (stamp, omega) = decode_imu(data).map_err(|e| {
            bad(format!(
                "topic {chosen}, IMU message {}: {e}",
                out.len() + 1
            ))
        })?;
        let t = if stamp == 0.0 {
            *log_time as f64 / 1e9
        } else {
            stamp
        };
        out.push(ImuMessage { t, omega });
    }
    Ok(out)
}

/// A CDR reader: alignment counts from the end of the 4-byte encapsulation
/// header, as the OMG CDR rules and ROS 2's Fast-CDR do.
struct Cdr<'a> {
    body: &'a [u8],
    pos: usize,
    little: bool,
}

impl Cdr<'_> {
    fn take(&mut self, n: usize, align: usize) -> std::result::Result<&[u8], String> {
        let start = self.pos.div_ceil(align) * align;
        let end = start
            .checked_add(n)
            .filter(|&e| e <= self.body.len())
            .ok_or_else(|| {
                format!(
                    "message ends at byte {} of {}, needs {} more",
                    self.body.len() + 4,
                    start + n + 4,
                    n
                )
            })?;
        self.pos = end;
        Ok(&self.body[start..end])
    }

    fn u32(&mut self) -> std::result::Result<u32, String> {
        let b: [u8; 4] = self.take(4, 4)?.try_into().map_err(|_| "u32".to_string())?;
        Ok(if self.little {
            u32::from_le_bytes(b)
        } else {
            u32::from_be_bytes(b)
        })
    }

    fn f64(&mut self) -> std::result::Result<f64, String> {
        let b: [u8; 8] = self.take(8, 8)?.try_into().map_err(|_| "f64".to_string())?;
        Ok(if self.little {
            f64::from_le_bytes(b)
        } else {
            f64::from_be_bytes(b)
        })
    }
}

/// Decodes a CDR `sensor_msgs/msg/Imu`: (header stamp in s, angular velocity in rad/s).
pub fn decode_imu(data: &[u8]) -> std::result::Result<(f64, DVec3), String> {
    if data.len() < 4 {
        return Err(format!("{} bytes, too short for CDR", data.len()));
    }
    let little = match (data[0], data[1]) {
        (0, 0) => false,
        (0, 1) => true,
        (a, b) => {
            return Err(format!(
                "CDR encapsulation {a:#04x}{b:02x} is not plain CDR (0x0000 or 0x0001)"
            ))
        }
    };
    let mut r = Cdr {
        body: &data[4..],
        pos: 0,
        little,
    };
    let sec = r.u32()? as i32;
    let nanosec = r.u32()?;
    let len = r.u32()? as usize;
    r.take(len, 1)?; // frame_id, with its NUL
    for _ in 0..4 + 9 {
        r.f64()?; // orientation, orientation_covariance
    }
    let w = DVec3::new(r.f64()?, r.f64()?, r.f64()?);
    for _ in 0..9 + 3 + 9 {
        // The rest must be there too: a shorter message is another type.
        r.f64()?;
    }
    if !w.is_finite() {
        return Err(format!("angular velocity {w} is not finite"));
    }
    Ok((sec as f64 + nanosec as f64 / 1e9, w))
}

/// The messages as gyro CSV text (`t,wx,wy,wz`, shortest round-trip
/// decimals), for the CSV reader's checks and options.
pub fn to_csv(messages: &[ImuMessage]) -> String {
    let mut s = String::from("t,wx,wy,wz\n");
    for m in messages {
        s.push_str(&format!(
            "{},{},{},{}\n",
            m.t, m.omega.x, m.omega.y, m.omega.z
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A CDR Imu built field by field (little-endian).
    fn message(frame: &str, w: [f64; 3]) -> Vec<u8> {
        let mut b = vec![0u8, 1, 0, 0];
        let pad = |b: &mut Vec<u8>, a: usize| {
            while (b.len() - 4) % a != 0 {
                b.push(0);
            }
        };
        b.extend(12i32.to_le_bytes());
        b.extend(500_000_000u32.to_le_bytes());
        b.extend((frame.len() as u32 + 1).to_le_bytes());
        b.extend(frame.as_bytes());
        b.push(0);
        for k in 0..13 {
            pad(&mut b, 8);
            b.extend((k as f64).to_le_bytes());
        }
        for x in w {
            b.extend(x.to_le_bytes());
        }
        for _ in 0..21 {
            b.extend(0f64.to_le_bytes());
        }
        b
    }

    #[test]
    fn decodes_every_frame_id_length() {
        for frame in ["", "a", "imu", "imu_link", "a_longer_frame_name"] {
            let (t, w) = decode_imu(&message(frame, [0.5, -1.25, 3.0])).unwrap();
            assert_eq!(t, 12.5);
            assert_eq!(w, DVec3::new(0.5, -1.25, 3.0));
        }
    }

    #[test]
    fn truncated_and_foreign_messages_are_errors() {
        let m = message("imu", [1.0, 2.0, 3.0]);
        for n in [0, 3, 4, 20, 150, m.len() - 200] {
            assert!(decode_imu(&m[..n]).is_err(), "{n} bytes");
        }
        let mut pl = m.clone();
        pl[1] = 3;
        assert!(decode_imu(&pl).unwrap_err().contains("not plain CDR"));
        let mut huge = m;
        huge[12..16].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(decode_imu(&huge).is_err());
    }
}
