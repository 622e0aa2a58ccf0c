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
//! The file is streamed twice, in bounded memory (one record or chunk at a
//! time, never the whole file): a first pass finds the IMU topics and checks
//! every record and IMU message, a second yields the chosen topic's samples
//! ([`ImuStream`]). A record may claim at most [`MAX_RECORD_BYTES`].

use crate::error::{Error, Result};
use ::mcap::sans_io::{LinearReaderOptions, MessageReadEvent, MessageReader};
use glam::DVec3;
use std::collections::BTreeMap;
use std::fs::File;
use std::io::Read;
use std::path::{Path, PathBuf};

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

/// Largest record an MCAP file may claim (a chunk's record included), bytes:
/// a damaged length is an error, not an allocation of that size.
pub const MAX_RECORD_BYTES: usize = 1 << 30;

/// Bytes read from the file at a time.
const READ_BYTES: usize = 1 << 16;

/// The messages of an MCAP file in file order, read from the file as the
/// reader asks for bytes (at most [`READ_BYTES`] at a time). A damaged
/// record is an error naming the file and the message number near it.
struct Messages {
    path: PathBuf,
    file: File,
    reader: MessageReader,
    /// Items yielded so far (messages and the error).
    items: usize,
    done: bool,
}

impl Messages {
    fn open(path: &Path) -> Result<Self> {
        // A regular file only (never a device or a pipe: it is read twice).
        let file = super::input::open_file(path)?;
        let options = LinearReaderOptions::default().with_record_length_limit(MAX_RECORD_BYTES);
        Ok(Messages {
            path: path.into(),
            file,
            reader: MessageReader::new_with_options(options),
            items: 0,
            done: false,
        })
    }

    fn bad(&self, what: String) -> Error {
        Error::invalid(self.path.display().to_string(), what)
    }

    /// Fills the reader's request for `need` bytes (fewer at the end of the file).
    fn read(&mut self, need: usize) -> Result<()> {
        let buf = self.reader.insert(need.clamp(1, READ_BYTES));
        let n = loop {
            match self.file.read(buf) {
                Ok(n) => break n,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                Err(e) => return Err(Error::io(&self.path, e)),
            }
        };
        self.reader.notify_read(n);
        Ok(())
    }
}

impl Iterator for Messages {
    type Item = Result<::mcap::Message<'static>>;

    fn next(&mut self) -> Option<Self::Item> {
        while !self.done {
            let event = match self.reader.next_event() {
                None => break,
                Some(e) => e,
            };
            match event {
                Ok(MessageReadEvent::ReadRequest(need)) => {
                    if let Err(e) = self.read(need) {
                        self.done = true;
                        return Some(Err(e));
                    }
                }
                Ok(MessageReadEvent::Message(m)) => {
                    self.items += 1;
                    return Some(Ok(m));
                }
                Err(e) => {
                    self.done = true;
                    self.items += 1;
                    let k = self.items;
                    return Some(Err(self.bad(format!("MCAP record near message {k}: {e}"))));
                }
            }
        }
        self.done = true;
        None
    }
}

/// True when `m` is on a channel of [`IMU_SCHEMA`] messages.
fn is_imu(m: &::mcap::Message) -> bool {
    m.channel
        .schema
        .as_ref()
        .is_some_and(|s| s.name == IMU_SCHEMA)
}

/// An IMU message's time: its header stamp, or its log time when the stamp is zero, s.
fn stamp_or_log_time(stamp: f64, log_time_ns: u64) -> f64 {
    if stamp == 0.0 {
        log_time_ns as f64 / 1e9
    } else {
        stamp
    }
}

/// What the first pass learns about one IMU topic.
#[derive(Default)]
struct TopicScan {
    messages: usize,
    /// The first message that does not decode: its number in the topic, why.
    first_bad: Option<(usize, String)>,
}

/// The first pass: every record read, every IMU message decoded, counted by topic.
fn scan(path: &Path) -> Result<BTreeMap<String, TopicScan>> {
    let mut topics: BTreeMap<String, TopicScan> = BTreeMap::new();
    for m in Messages::open(path)? {
        let m = m?;
        if !is_imu(&m) {
            continue;
        }
        let ch = &m.channel;
        let entry = topics.entry(ch.topic.clone()).or_default();
        entry.messages += 1;
        if ch.message_encoding != "cdr" {
            return Err(Error::invalid(
                path.display().to_string(),
                format!(
                    "topic {}: message encoding '{}', expected 'cdr'",
                    ch.topic, ch.message_encoding
                ),
            ));
        }
        if entry.first_bad.is_none() {
            if let Err(e) = decode_imu(&m.data) {
                entry.first_bad = Some((entry.messages, e));
            }
        }
    }
    Ok(topics)
}

/// The topic read: `topic` if it has IMU messages, else the only IMU topic.
fn choose(
    path: &Path,
    topics: &BTreeMap<String, TopicScan>,
    topic: Option<&str>,
) -> Result<String> {
    let bad = |what: String| Error::invalid(path.display().to_string(), what);
    let list = || {
        if topics.is_empty() {
            "none".to_string()
        } else {
            topics
                .iter()
                .map(|(t, s)| format!("{t} ({} messages)", s.messages))
                .collect::<Vec<_>>()
                .join(", ")
        }
    };
    match topic {
        Some(t) if topics.contains_key(t) => Ok(t.to_string()),
        Some(t) => Err(bad(format!(
            "no {IMU_SCHEMA} messages on topic '{t}'; IMU topics: {}",
            list()
        ))),
        None if topics.len() == 1 => Ok(topics.keys().next().cloned().unwrap_or_default()),
        None => Err(bad(format!(
            "choose an IMU topic with --topic; IMU topics: {}",
            list()
        ))),
    }
}

/// The IMU messages of one topic of an MCAP file, in file order, streamed
/// in bounded memory. [`ImuStream::open`] checks the whole file first (its
/// records, the topic, every message of the topic), so a damaged file is an
/// error before the first sample.
pub struct ImuStream {
    messages: Messages,
    topic: String,
    count: usize,
}

impl ImuStream {
    /// Opens the MCAP file at `path` for the IMU messages of `topic` (None:
    /// the only IMU topic in the file).
    pub fn open(path: &Path, topic: Option<&str>) -> Result<Self> {
        let topics = scan(path)?;
        let chosen = choose(path, &topics, topic)?;
        if let Some((k, e)) = topics.get(&chosen).and_then(|s| s.first_bad.as_ref()) {
            return Err(Error::invalid(
                path.display().to_string(),
                format!("topic {chosen}, IMU message {k}: {e}"),
            ));
        }
        Ok(ImuStream {
            messages: Messages::open(path)?,
            topic: chosen,
            count: 0,
        })
    }

    /// Messages yielded so far.
    pub fn messages_read(&self) -> usize {
        self.count
    }
}

impl Iterator for ImuStream {
    type Item = Result<ImuMessage>;

    fn next(&mut self) -> Option<Self::Item> {
        loop {
            let m = match self.messages.next()? {
                Ok(m) => m,
                Err(e) => return Some(Err(e)),
            };
            if !is_imu(&m) || m.channel.topic != self.topic {
                continue;
            }
            self.count += 1;
            // Checked by the first pass; an error here means the file changed.
            return Some(match decode_imu(&m.data) {
                Ok((stamp, omega)) => Ok(ImuMessage {
                    t: stamp_or_log_time(stamp, m.log_time),
                    omega,
                }),
                Err(e) => Err(self.messages.bad(format!(
                    "topic {}, IMU message {}: {e}",
                    self.topic, self.count
                ))),
            });
        }
    }
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
