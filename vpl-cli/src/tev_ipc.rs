//! A client of the [tev](https://github.com/Tom94/tev) image viewer's IPC
//! protocol, so that a long render can be watched as it converges.
//!
//! tev listens on TCP (by default `127.0.0.1:14158`). Every packet is a
//! little-endian `u32` length (the whole packet, these four bytes included),
//! a one-byte type, then the fields: booleans as one byte, strings
//! NUL-terminated, `i32` sizes, `i64` offsets and strides, `f32` pixels.
//! The client sends three of the protocol's packets:
//!
//! - **CreateImage** (type 4): focus, name, width, height, channel count
//!   and names. A new black image (tev replaces one of the same name).
//! - **UpdateImage, version 3** (type 6): focus, name, channel count and
//!   names, the region `x, y, width, height`, each channel's offset and
//!   stride into the pixel data, then the data. Pixels are sent
//!   interleaved (`R G B R G B …`: offsets 0, 1, 2 and strides 3), row by
//!   row, in packets of at most [`MAX_UPDATE_PIXELS`] pixels.
//! - **CloseImage** (type 2): name.
//!
//! ```no_run
//! use vpl_core::Image;
//! use vpl_cli::tev_ipc::TevClient;
//! # fn main() -> Result<(), vpl_cli::tev_ipc::TevError> {
//! let mut tev = TevClient::connect("127.0.0.1:14158")?;
//! let img = Image::new(64, 48);
//! tev.create_rgb("render", img.width, img.height)?;
//! tev.update_rgb("render", &img, (0, 0, 64, 48))?;
//! # Ok(())
//! # }
//! ```

use std::io::Write;
use std::net::{TcpStream, ToSocketAddrs};
use std::time::Duration;
use vpl_core::Image;
use vpl_core::glam::Vec3;

/// The port tev listens on unless told otherwise.
pub const DEFAULT_PORT: u16 = 14158;

/// Most pixels one UpdateImage packet carries (12 MiB of RGB): larger
/// regions are sent as several packets of whole rows.
pub const MAX_UPDATE_PIXELS: usize = 1 << 20;

/// How long the client waits to connect, and for a send to complete.
const TIMEOUT: Duration = Duration::from_secs(5);

const CLOSE_IMAGE: u8 = 2;
const CREATE_IMAGE: u8 = 4;
const UPDATE_IMAGE_V3: u8 = 6;

/// Errors of talking to tev.
#[derive(Debug, thiserror::Error)]
pub enum TevError {
    /// The address does not name a host and port.
    #[error("tev address '{0}' is not HOST:PORT")]
    Address(String),
    /// Nothing accepted the connection.
    #[error("cannot reach tev at {address}: {source}")]
    Connect {
        /// The address tried.
        address: String,
        /// Why.
        source: std::io::Error,
    },
    /// The connection failed while sending.
    #[error("sending to tev failed: {0}")]
    Send(#[from] std::io::Error),
    /// An image or channel name holds a NUL byte, which ends strings in the
    /// protocol.
    #[error("tev names may not contain NUL bytes ({0:?})")]
    Name(String),
    /// The region lies outside the image, or the image is too large for the
    /// protocol's 32-bit sizes.
    #[error("region {x},{y} {w}x{h} does not fit the {width}x{height} image")]
    Region {
        /// Left edge.
        x: u32,
        /// Top edge.
        y: u32,
        /// Width.
        w: u32,
        /// Height.
        h: u32,
        /// The image's width.
        width: u32,
        /// The image's height.
        height: u32,
    },
}

/// A connection to a running tev.
#[derive(Debug)]
pub struct TevClient {
    stream: TcpStream,
}

/// A packet being written: the length is filled in by [`Packet::finish`].
struct Packet(Vec<u8>);

impl Packet {
    fn new(kind: u8) -> Packet {
        Packet(vec![0, 0, 0, 0, kind])
    }
    fn bool(&mut self, b: bool) {
        self.0.push(b as u8);
    }
    fn str(&mut self, s: &str) -> Result<(), TevError> {
        if s.contains('\0') {
            return Err(TevError::Name(s.into()));
        }
        self.0.extend_from_slice(s.as_bytes());
        self.0.push(0);
        Ok(())
    }
    fn i32(&mut self, v: i32) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn i64(&mut self, v: i64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn f32(&mut self, v: f32) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn finish(mut self) -> Vec<u8> {
        // At most MAX_UPDATE_PIXELS · 12 bytes plus names: far below 4 GiB.
        let n = self.0.len() as u32;
        self.0[..4].copy_from_slice(&n.to_le_bytes());
        self.0
    }
}

/// `v` as the protocol's `i32`, or the region error.
fn size(v: u32, region: impl Fn() -> TevError) -> Result<i32, TevError> {
    i32::try_from(v).map_err(|_| region())
}

impl TevClient {
    /// Connects to tev at `address` (`HOST:PORT`, or `HOST` for the default
    /// port), waiting at most five seconds.
    pub fn connect(address: &str) -> Result<TevClient, TevError> {
        let with_port = if address.rsplit_once(':').is_some_and(|(_, p)| p.parse::<u16>().is_ok()) {
            address.to_string()
        } else {
            format!("{address}:{DEFAULT_PORT}")
        };
        let addrs: Vec<_> = with_port.to_socket_addrs().map_err(|_| TevError::Address(address.into()))?.collect();
        let mut last = None;
        for a in &addrs {
            match TcpStream::connect_timeout(a, TIMEOUT) {
                Ok(stream) => {
                    stream.set_write_timeout(Some(TIMEOUT)).map_err(TevError::Send)?;
                    // Small packets (create, close) go out at once.
                    stream.set_nodelay(true).map_err(TevError::Send)?;
                    return Ok(TevClient { stream });
                }
                Err(e) => last = Some(e),
            }
        }
        Err(TevError::Connect {
            address: address.into(),
            source: last.unwrap_or_else(|| std::io::Error::new(std::io::ErrorKind::NotFound, "the name resolves to no address")),
        })
    }

    /// Wraps a connection made elsewhere.
    pub fn from_stream(stream: TcpStream) -> TevClient {
        TevClient { stream }
    }

    fn send(&mut self, p: Packet) -> Result<(), TevError> {
        self.stream.write_all(&p.finish())?;
        Ok(())
    }

    /// Creates (or replaces) a black `width`×`height` image `name` with
    /// channels R, G and B, and brings it to the front.
    pub fn create_rgb(&mut self, name: &str, width: u32, height: u32) -> Result<(), TevError> {
        let region = || TevError::Region { x: 0, y: 0, w: width, h: height, width, height };
        let mut p = Packet::new(CREATE_IMAGE);
        p.bool(true);
        p.str(name)?;
        p.i32(size(width, region)?);
        p.i32(size(height, region)?);
        p.i32(3);
        for c in ["R", "G", "B"] {
            p.str(c)?;
        }
        self.send(p)
    }

    /// Sends the pixels of `image` inside `region` (`x, y, width, height`)
    /// to image `name`, as packets of at most [`MAX_UPDATE_PIXELS`] pixels
    /// (whole rows). The image must have been created at `image`'s size.
    pub fn update_rgb(&mut self, name: &str, image: &Image, region: (u32, u32, u32, u32)) -> Result<(), TevError> {
        let (x, y, w, h) = region;
        let bad = || TevError::Region { x, y, w, h, width: image.width, height: image.height };
        if w == 0 || h == 0 || x.checked_add(w).is_none_or(|e| e > image.width) || y.checked_add(h).is_none_or(|e| e > image.height) {
            return Err(bad());
        }
        size(image.width, bad)?;
        size(image.height, bad)?;
        self.send_region(name, region, |dx, dy| image.get(x + dx, y + dy))
    }

    /// Sends `pixels` (`width · height` values, row-major) as the region
    /// `(x, y, width, height)` of image `name`: a finished tile of a render.
    pub fn update_tile(&mut self, name: &str, region: (u32, u32, u32, u32), pixels: &[Vec3]) -> Result<(), TevError> {
        let (x, y, w, h) = region;
        let bad = || TevError::Region { x, y, w, h, width: w, height: h };
        if w == 0 || h == 0 || pixels.len() as u64 != w as u64 * h as u64 {
            return Err(bad());
        }
        if x.checked_add(w).is_none_or(|e| i32::try_from(e).is_err()) || y.checked_add(h).is_none_or(|e| i32::try_from(e).is_err()) {
            return Err(bad());
        }
        self.send_region(name, region, |dx, dy| pixels[(dy * w + dx) as usize])
    }

    /// The UpdateImage packets of a checked region whose pixel (dx, dy),
    /// relative to its corner, is `at(dx, dy)`.
    fn send_region(&mut self, name: &str, region: (u32, u32, u32, u32), at: impl Fn(u32, u32) -> Vec3) -> Result<(), TevError> {
        let (x, y, w, h) = region;
        if name.contains('\0') {
            return Err(TevError::Name(name.into()));
        }
        let rows_per_packet = (MAX_UPDATE_PIXELS / w as usize).max(1) as u32;
        let mut row = 0;
        while row < h {
            let rows = rows_per_packet.min(h - row);
            let mut p = Packet::new(UPDATE_IMAGE_V3);
            p.bool(false);
            p.str(name)?;
            p.i32(3);
            for c in ["R", "G", "B"] {
                p.str(c)?;
            }
            // The callers checked that x + w and y + h fit an i32.
            p.i32(x as i32);
            p.i32((y + row) as i32);
            p.i32(w as i32);
            p.i32(rows as i32);
            for offset in 0..3 {
                p.i64(offset);
            }
            for _ in 0..3 {
                p.i64(3);
            }
            p.0.reserve(w as usize * rows as usize * 12);
            for dy in row..row + rows {
                for dx in 0..w {
                    let c = at(dx, dy);
                    p.f32(c.x);
                    p.f32(c.y);
                    p.f32(c.z);
                }
            }
            self.send(p)?;
            row += rows;
        }
        Ok(())
    }

    /// Sends all of `image` to image `name`.
    pub fn update_whole(&mut self, name: &str, image: &Image) -> Result<(), TevError> {
        self.update_rgb(name, image, (0, 0, image.width, image.height))
    }

    /// Closes image `name` in tev.
    pub fn close(&mut self, name: &str) -> Result<(), TevError> {
        let mut p = Packet::new(CLOSE_IMAGE);
        p.str(name)?;
        self.send(p)
    }
}

/// What a test's server reads back: one decoded packet.
#[doc(hidden)]
#[derive(Clone, Debug, PartialEq)]
pub enum Decoded {
    /// CreateImage: name, width, height, channels.
    Create(String, i32, i32, Vec<String>),
    /// UpdateImage v3: name, channels, region, offsets, strides, data.
    Update(String, Vec<String>, [i32; 4], Vec<i64>, Vec<i64>, Vec<f32>),
    /// CloseImage: name.
    Close(String),
}

/// Decodes the packets of `bytes` (a whole stream as a server received
/// it), or says what is malformed: an independent reading of the protocol
/// for tests of the client and of programs that stream to tev.
#[doc(hidden)]
pub fn decode_stream(bytes: &[u8]) -> Result<Vec<Decoded>, String> {
    struct R<'a>(&'a [u8]);
    impl R<'_> {
        fn take(&mut self, n: usize) -> Result<&[u8], String> {
            if self.0.len() < n {
                return Err(format!("{n} bytes wanted, {} left", self.0.len()));
            }
            let (a, b) = self.0.split_at(n);
            self.0 = b;
            Ok(a)
        }
        fn u8(&mut self) -> Result<u8, String> {
            Ok(self.take(1)?[0])
        }
        fn i32(&mut self) -> Result<i32, String> {
            Ok(i32::from_le_bytes(self.take(4)?.try_into().map_err(|_| "short i32")?))
        }
        fn i64(&mut self) -> Result<i64, String> {
            Ok(i64::from_le_bytes(self.take(8)?.try_into().map_err(|_| "short i64")?))
        }
        fn str(&mut self) -> Result<String, String> {
            let end = self.0.iter().position(|&b| b == 0).ok_or("unterminated string")?;
            let s = String::from_utf8(self.0[..end].to_vec()).map_err(|e| e.to_string())?;
            self.0 = &self.0[end + 1..];
            Ok(s)
        }
    }
    let mut out = Vec::new();
    let mut rest = bytes;
    while !rest.is_empty() {
        let mut head = R(rest);
        let len = head.i32()? as usize;
        if len < 5 || len > rest.len() {
            return Err(format!("packet length {len} with {} bytes left", rest.len()));
        }
        let mut r = R(&rest[4..len]);
        let packet = match r.u8()? {
            CREATE_IMAGE => {
                let _focus = r.u8()?;
                let name = r.str()?;
                let (w, h, n) = (r.i32()?, r.i32()?, r.i32()?);
                let channels = (0..n).map(|_| r.str()).collect::<Result<_, _>>()?;
                Decoded::Create(name, w, h, channels)
            }
            UPDATE_IMAGE_V3 => {
                let _focus = r.u8()?;
                let name = r.str()?;
                let n = r.i32()?;
                let channels: Vec<String> = (0..n).map(|_| r.str()).collect::<Result<_, _>>()?;
                let region = [r.i32()?, r.i32()?, r.i32()?, r.i32()?];
                let offsets: Vec<i64> = (0..n).map(|_| r.i64()).collect::<Result<_, _>>()?;
                let strides: Vec<i64> = (0..n).map(|_| r.i64()).collect::<Result<_, _>>()?;
                if r.0.len() % 4 != 0 {
                    return Err("pixel data is not whole floats".into());
                }
                let data = r.0.chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect();
                r.0 = &[];
                Decoded::Update(name, channels, region, offsets, strides, data)
            }
            CLOSE_IMAGE => Decoded::Close(r.str()?),
            other => return Err(format!("unknown packet type {other}")),
        };
        if !r.0.is_empty() {
            return Err(format!("{} bytes left over in a packet", r.0.len()));
        }
        out.push(packet);
        rest = &rest[len..];
    }
    Ok(out)
}

/// The image `name` that `packets` leave behind: created at its size, each
/// update written into it (interleaved RGB as [`TevClient`] sends).
#[doc(hidden)]
pub fn replay(packets: &[Decoded], name: &str) -> Option<Image> {
    let mut img: Option<Image> = None;
    for p in packets {
        match p {
            Decoded::Create(n, w, h, _) if n == name => img = Some(Image::new(*w as u32, *h as u32)),
            Decoded::Update(n, _, [x, y, w, h], _, _, data) if n == name => {
                let img = img.as_mut()?;
                for (i, c) in data.chunks_exact(3).enumerate() {
                    let (px, py) = (*x as u32 + i as u32 % *w as u32, *y as u32 + i as u32 / *w as u32);
                    if px < img.width && py < img.height && (i as i32) < w * h {
                        img.set(px, py, Vec3::new(c[0], c[1], c[2]));
                    }
                }
            }
            _ => {}
        }
    }
    img
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Read;
    use std::net::TcpListener;

    /// A server on a free port that reads everything one client sends.
    fn server() -> (String, std::thread::JoinHandle<Vec<u8>>) {
        let l = TcpListener::bind("127.0.0.1:0").unwrap();
        let addr = l.local_addr().unwrap().to_string();
        let h = std::thread::spawn(move || {
            let (mut s, _) = l.accept().unwrap();
            let mut buf = Vec::new();
            s.read_to_end(&mut buf).unwrap();
            buf
        });
        (addr, h)
    }

    /// Create, two region updates (one split into packets by rows) and a
    /// close arrive as the protocol lays them out, and replaying them gives
    /// back the image's pixels in the regions sent.
    #[test]
    fn packets_decode_and_replay_to_the_image() {
        let (addr, h) = server();
        let mut img = Image::new(7, 5);
        for y in 0..5 {
            for x in 0..7 {
                img.set(x, y, Vec3::new(x as f32, y as f32, 0.5 + (x * y) as f32));
            }
        }
        let mut c = TevClient::connect(&addr).unwrap();
        c.create_rgb("frame", 7, 5).unwrap();
        c.update_rgb("frame", &img, (0, 0, 7, 5)).unwrap();
        c.update_rgb("frame", &img, (2, 1, 3, 2)).unwrap();
        c.update_tile("frame", (5, 3, 2, 2), &[img.get(5, 3), img.get(6, 3), img.get(5, 4), img.get(6, 4)]).unwrap();
        c.close("frame").unwrap();
        drop(c);
        let packets = decode_stream(&h.join().unwrap()).unwrap();
        assert_eq!(packets.len(), 5);
        assert_eq!(packets[0], Decoded::Create("frame".into(), 7, 5, vec!["R".into(), "G".into(), "B".into()]));
        match &packets[2] {
            Decoded::Update(n, ch, region, offsets, strides, data) => {
                assert_eq!((n.as_str(), ch.len()), ("frame", 3));
                assert_eq!(*region, [2, 1, 3, 2]);
                assert_eq!((offsets.as_slice(), strides.as_slice()), ([0, 1, 2].as_slice(), [3, 3, 3].as_slice()));
                assert_eq!(data.len(), 3 * 2 * 3);
                assert_eq!(&data[..3], &[2.0, 1.0, 2.5]);
            }
            other => panic!("{other:?}"),
        }
        assert_eq!(packets[4], Decoded::Close("frame".into()));
        assert_eq!(replay(&packets, "frame").unwrap().data, img.data);
    }

    /// A region of more than MAX_UPDATE_PIXELS goes out as several packets
    /// of whole rows that together cover it.
    #[test]
    fn large_regions_are_split_into_rows() {
        let (addr, h) = server();
        let (w, hh) = (1500u32, 1000u32);
        let img = Image::new(w, hh);
        let mut c = TevClient::connect(&addr).unwrap();
        c.update_whole("big", &img).unwrap();
        drop(c);
        let packets = decode_stream(&h.join().unwrap()).unwrap();
        let rows: Vec<[i32; 4]> = packets
            .iter()
            .map(|p| match p {
                Decoded::Update(_, _, r, ..) => *r,
                other => panic!("{other:?}"),
            })
            .collect();
        assert!(rows.len() == 2, "{rows:?}");
        assert!(rows.iter().all(|r| r[2] as usize * r[3] as usize <= MAX_UPDATE_PIXELS && r[0] == 0 && r[2] == w as i32));
        assert_eq!(rows.iter().map(|r| r[3]).sum::<i32>(), hh as i32);
        assert_eq!(rows[1][1], rows[0][3]);
    }

    /// Bad input is a typed error, never a panic or a malformed packet.
    #[test]
    fn bad_names_regions_and_addresses_are_errors() {
        let (addr, h) = server();
        let img = Image::new(4, 4);
        let mut c = TevClient::connect(&addr).unwrap();
        assert!(matches!(c.create_rgb("a\0b", 4, 4), Err(TevError::Name(_))));
        assert!(matches!(c.update_rgb("x", &img, (3, 0, 2, 1)), Err(TevError::Region { .. })));
        assert!(matches!(c.update_rgb("x", &img, (0, 0, 0, 1)), Err(TevError::Region { .. })));
        assert!(matches!(c.update_rgb("x", &img, (u32::MAX, 0, 2, 1)), Err(TevError::Region { .. })));
        assert!(matches!(c.create_rgb("x", u32::MAX, 1), Err(TevError::Region { .. })));
        assert!(matches!(c.update_tile("x", (0, 0, 2, 2), &[Vec3::ZERO; 3]), Err(TevError::Region { .. })));
        assert!(matches!(c.update_tile("x", (i32::MAX as u32, 0, 2, 1), &[Vec3::ZERO; 2]), Err(TevError::Region { .. })));
        drop(c);
        // None of the refused calls sent anything.
        assert!(h.join().unwrap().is_empty());
        assert!(matches!(TevClient::connect("no port here:"), Err(TevError::Address(_)) | Err(TevError::Connect { .. })));
        // A port nothing listens on (bound, then freed).
        let free = TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap();
        assert!(matches!(TevClient::connect(&free.to_string()), Err(TevError::Connect { .. })));
    }
}
