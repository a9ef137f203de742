//! Binary STL, streamed: triangles are written as they come (e.g. brick by
//! brick) and the count in the header is patched at the end.

use std::io::{Seek, SeekFrom, Write};

pub struct StlWriter<W: Write + Seek> {
    w: W,
    count: u64,
}

impl<W: Write + Seek> StlWriter<W> {
    pub fn new(mut w: W) -> std::io::Result<Self> {
        let mut header = [0u8; 80];
        let tag = b"binary STL written by microfrep";
        header[..tag.len()].copy_from_slice(tag);
        w.write_all(&header)?;
        w.write_all(&0u32.to_le_bytes())?;
        Ok(StlWriter { w, count: 0 })
    }

    /// Appends one triangle (counter-clockwise from outside); its facet
    /// normal is computed from the corners.
    pub fn push(&mut self, t: [[f32; 3]; 3]) -> std::io::Result<()> {
        let [p, q, r] = t.map(|v| v.map(|c| c as f64));
        let e1 = [q[0] - p[0], q[1] - p[1], q[2] - p[2]];
        let e2 = [r[0] - p[0], r[1] - p[1], r[2] - p[2]];
        let n = [
            e1[1] * e2[2] - e1[2] * e2[1],
            e1[2] * e2[0] - e1[0] * e2[2],
            e1[0] * e2[1] - e1[1] * e2[0],
        ];
        let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        let n = if len > 0.0 { n.map(|c| c / len) } else { n };
        let mut rec = [0u8; 50];
        let vals = n
            .iter()
            .map(|&c| c as f32)
            .chain(t.iter().flatten().copied());
        for (k, v) in vals.enumerate() {
            rec[4 * k..4 * k + 4].copy_from_slice(&v.to_le_bytes());
        }
        self.w.write_all(&rec)?;
        self.count += 1;
        Ok(())
    }

    /// Patches the triangle count and returns the inner writer.
    pub fn finish(mut self) -> std::io::Result<W> {
        let n = u32::try_from(self.count).map_err(|_| {
            std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                "binary STL holds at most 2^32-1 triangles",
            )
        })?;
        self.w.seek(SeekFrom::Start(80))?;
        self.w.write_all(&n.to_le_bytes())?;
        self.w.seek(SeekFrom::End(0))?;
        self.w.flush()?;
        Ok(self.w)
    }
}
