//! The byte form of an FMU state (fmi2SerializeFMUstate): a magic tag, a
//! format version and the unit's GUID, then the snapshot's numbers as
//! little-endian IEEE 754 doubles, so a restored state is bit for bit the
//! saved one, and last a CRC-32 of everything before it. Anything that does
//! not parse, fails its checksum, or belongs to another unit, is refused
//! with the reason.

use fistage_sim::{Checkpoint, StepCounts};

use crate::phase::Phase;

/// Everything that changes while an instance runs; an FMU state is a copy of it.
#[derive(Debug, Clone, PartialEq)]
pub struct Snapshot {
    pub(crate) phase: Phase,
    pub(crate) values: Vec<f64>,
    pub(crate) start_time: f64,
    pub(crate) stop_time: Option<f64>,
    pub(crate) tolerance: Option<f64>,
    pub(crate) checkpoint: Option<Checkpoint>,
}

const MAGIC: &[u8; 8] = b"FISTAGE\0";
const VERSION: u32 = 2;
/// Bytes of the trailing CRC-32.
const CHECKSUM: usize = 4;

struct Writer(Vec<u8>);

impl Writer {
    fn u32(&mut self, v: u32) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn u64(&mut self, v: u64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn f64(&mut self, v: f64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn optional(&mut self, v: Option<f64>) {
        self.0.push(u8::from(v.is_some()));
        self.f64(v.unwrap_or(0.0));
    }
    fn slice(&mut self, values: &[f64]) {
        self.u64(values.len() as u64);
        values.iter().for_each(|v| self.f64(*v));
    }
    fn bytes(&mut self, bytes: &[u8]) {
        self.u64(bytes.len() as u64);
        self.0.extend_from_slice(bytes);
    }
}

struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Result<&'a [u8], String> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.bytes.len());
        let Some(end) = end else {
            return Err(format!(
                "FMU state is truncated ({} bytes, needed more at byte {})",
                self.bytes.len(),
                self.at
            ));
        };
        let out = &self.bytes[self.at..end];
        self.at = end;
        Ok(out)
    }
    fn array<const N: usize>(&mut self) -> Result<[u8; N], String> {
        let mut out = [0u8; N];
        out.copy_from_slice(self.take(N)?);
        Ok(out)
    }
    fn u8(&mut self) -> Result<u8, String> {
        Ok(self.take(1)?[0])
    }
    fn u64(&mut self) -> Result<u64, String> {
        Ok(u64::from_le_bytes(self.array()?))
    }
    fn f64(&mut self) -> Result<f64, String> {
        Ok(f64::from_le_bytes(self.array()?))
    }
    fn optional(&mut self) -> Result<Option<f64>, String> {
        let present = self.u8()? != 0;
        let value = self.f64()?;
        Ok(present.then_some(value))
    }
    fn length(&mut self, element_size: usize) -> Result<usize, String> {
        let n = self.u64()?;
        let remaining = (self.bytes.len() - self.at) as u64;
        if n.saturating_mul(element_size as u64) > remaining {
            return Err(format!(
                "FMU state is corrupt: a length of {n} at byte {}",
                self.at
            ));
        }
        Ok(n as usize)
    }
    fn slice(&mut self) -> Result<Vec<f64>, String> {
        let n = self.length(8)?;
        (0..n).map(|_| self.f64()).collect()
    }
}

/// The bytes of a snapshot of the unit with this GUID.
pub fn encode(guid: &str, snapshot: &Snapshot) -> Vec<u8> {
    let mut w = Writer(Vec::new());
    w.0.extend_from_slice(MAGIC);
    w.u32(VERSION);
    w.bytes(guid.as_bytes());
    w.0.push(snapshot.phase.code());
    w.slice(&snapshot.values);
    w.f64(snapshot.start_time);
    w.optional(snapshot.stop_time);
    w.optional(snapshot.tolerance);
    match &snapshot.checkpoint {
        None => w.0.push(0),
        Some(c) => {
            w.0.push(1);
            w.f64(c.t);
            w.f64(c.h);
            w.u64(c.counts.steps);
            w.u64(c.counts.rejected);
            w.u64(c.counts.rhs_evaluations);
            w.slice(&c.x);
        }
    }
    let checksum = crc32fast::hash(&w.0);
    w.u32(checksum);
    w.0
}

/// A snapshot from bytes made by [`encode`] for the unit with this GUID.
pub fn decode(guid: &str, bytes: &[u8]) -> Result<Snapshot, String> {
    if !bytes.starts_with(MAGIC) {
        return Err("not a fistage FMU state (bad magic bytes)".into());
    }
    let version_at = MAGIC.len();
    let version = bytes
        .get(version_at..version_at + 4)
        .and_then(|b| b.try_into().ok())
        .map(u32::from_le_bytes);
    if version != Some(VERSION) {
        return Err(match version {
            Some(v) => format!("FMU state format version {v}, this unit reads {VERSION}"),
            None => "FMU state is truncated (no format version)".into(),
        });
    }
    let Some(body_len) = bytes.len().checked_sub(CHECKSUM) else {
        return Err("FMU state is truncated (no checksum)".into());
    };
    let (body, stored) = bytes.split_at(body_len);
    let stored = u32::from_le_bytes(stored.try_into().map_err(|_| "FMU state is truncated")?);
    if crc32fast::hash(body) != stored {
        return Err("FMU state is corrupt: its checksum does not match its contents".into());
    }
    let bytes = body;
    let mut r = Reader {
        bytes,
        at: version_at + 4,
    };
    let n = r.length(1)?;
    let owner = r.take(n)?;
    if owner != guid.as_bytes() {
        return Err(format!(
            "FMU state was saved by unit {}, this is {guid}",
            String::from_utf8_lossy(owner)
        ));
    }
    let phase = Phase::from_code(r.u8()?).ok_or("FMU state is corrupt: unknown phase")?;
    let values = r.slice()?;
    let start_time = r.f64()?;
    let stop_time = r.optional()?;
    let tolerance = r.optional()?;
    let checkpoint = match r.u8()? {
        0 => None,
        1 => {
            let t = r.f64()?;
            let h = r.f64()?;
            let counts = StepCounts {
                steps: r.u64()?,
                rejected: r.u64()?,
                rhs_evaluations: r.u64()?,
            };
            let x = r.slice()?;
            Some(Checkpoint { t, x, h, counts })
        }
        other => return Err(format!("FMU state is corrupt: checkpoint flag {other}")),
    };
    if phase == Phase::Fatal {
        return Err("FMU state is corrupt: it records a fatal error".into());
    }
    if matches!(
        phase,
        Phase::StepComplete
            | Phase::StepFailed
            | Phase::Terminated
            | Phase::EventMode
            | Phase::ContinuousTime
    ) && checkpoint.is_none()
    {
        return Err("FMU state is corrupt: a stepping phase without a state vector".into());
    }
    if r.at != bytes.len() {
        return Err(format!(
            "FMU state has {} bytes after its end",
            bytes.len() - r.at
        ));
    }
    Ok(Snapshot {
        phase,
        values,
        start_time,
        stop_time,
        tolerance,
        checkpoint,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Snapshot {
        Snapshot {
            phase: Phase::StepComplete,
            values: vec![6e4, 100.0, f64::MIN_POSITIVE, -0.0],
            start_time: 0.0,
            stop_time: Some(5.0),
            tolerance: None,
            checkpoint: Some(Checkpoint {
                t: 0.125,
                x: vec![1e-6, -3.0e-300, 0.1 + 0.2],
                h: 1.5e-5,
                counts: StepCounts {
                    steps: 7,
                    rejected: 1,
                    rhs_evaluations: 50,
                },
            }),
        }
    }

    #[test]
    fn round_trip_is_bit_exact() {
        let snapshot = sample();
        let bytes = encode("{guid}", &snapshot);
        let back = decode("{guid}", &bytes).expect("decodes");
        assert_eq!(back, snapshot);
        assert_eq!(back.values[3].to_bits(), (-0.0f64).to_bits());
    }

    #[test]
    fn every_truncation_and_foreign_state_is_refused() {
        let bytes = encode("{guid}", &sample());
        for n in 0..bytes.len() {
            assert!(
                decode("{guid}", &bytes[..n]).is_err(),
                "prefix of {n} bytes"
            );
        }
        let error = decode("{other}", &bytes).expect_err("other unit");
        assert!(error.contains("saved by unit {guid}"), "{error}");
        let mut longer = bytes.clone();
        longer.push(0);
        assert!(decode("{guid}", &longer).is_err());
    }

    /// Every flipped bit, in the numbers as anywhere else, is refused.
    #[test]
    fn corrupted_states_are_refused() {
        let bytes = encode("{guid}", &sample());
        for i in 0..bytes.len() {
            for bit in 0..8 {
                let mut damaged = bytes.clone();
                damaged[i] ^= 1 << bit;
                assert!(
                    decode("{guid}", &damaged).is_err(),
                    "byte {i} bit {bit} flipped went through"
                );
            }
        }
    }
}
