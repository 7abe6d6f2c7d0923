//! Whether the display a window would open on speaks its protocol. winit connects to the
//! Wayland compositor or the X server the environment names and waits for ever on one that
//! accepts the connection and then says nothing, or says something that is not its
//! protocol; so first one request is sent there, whose whole reply must come within
//! [`ANSWER_WITHIN`] and read as the protocol's: the program then says what is wrong with
//! which display instead of hanging.

use std::io::{Read, Write};
use std::net::{TcpStream, ToSocketAddrs};
use std::os::unix::net::UnixStream;
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// How long a display has to answer, in all.
pub const ANSWER_WITHIN: Duration = Duration::from_secs(5);

/// Where a display listens, as the environment names it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Display {
    /// A Wayland compositor's socket.
    Wayland(PathBuf),
    /// An X server's local socket (display number `n`).
    X11Local(u32),
    /// An X server over TCP: host and display number.
    X11Tcp(String, u32),
}

impl Display {
    /// The display winit opens a window on: Wayland where `WAYLAND_DISPLAY` is set (a path,
    /// or a name in `XDG_RUNTIME_DIR`), else X11's `DISPLAY`; `None` where neither names
    /// one this check knows how to reach (winit then reports what it finds).
    pub fn from_env() -> Option<Display> {
        let var = |name: &str| std::env::var(name).ok().filter(|v| !v.is_empty());
        if let Some(wayland) = var("WAYLAND_DISPLAY") {
            let path = PathBuf::from(&wayland);
            return match path.is_absolute() {
                true => Some(Display::Wayland(path)),
                false => var("XDG_RUNTIME_DIR")
                    .map(|dir| Display::Wayland(PathBuf::from(dir).join(path))),
            };
        }
        Display::x11(&var("DISPLAY")?)
    }

    /// The X11 display `[host]:number[.screen]` names (`unix` or no host: the local
    /// socket).
    pub fn x11(name: &str) -> Option<Display> {
        let (host, rest) = name.rsplit_once(':')?;
        let number = rest.split('.').next()?.parse().ok()?;
        match host {
            "" | "unix" => Some(Display::X11Local(number)),
            host if host.contains('/') => None,
            host => Some(Display::X11Tcp(host.to_owned(), number)),
        }
    }

    /// `Ok` if the display answers one request in its protocol, the whole reply within
    /// `timeout`; otherwise what is wrong, in words that name it.
    pub fn answers(&self, timeout: Duration) -> Result<(), String> {
        let deadline = Instant::now() + timeout;
        let result = match self {
            Display::Wayland(path) => UnixStream::connect(path)
                .map_err(Refusal::Unreachable)
                .and_then(|s| ask(s, &WAYLAND_SYNC, deadline, wayland_reply)),
            Display::X11Local(n) => UnixStream::connect(format!("/tmp/.X11-unix/X{n}"))
                .map_err(Refusal::Unreachable)
                .and_then(|s| ask(s, &X11_SETUP, deadline, x11_reply)),
            Display::X11Tcp(host, n) => {
                let port = 6000u16.saturating_add(u16::try_from(*n).unwrap_or(u16::MAX));
                (host.as_str(), port)
                    .to_socket_addrs()
                    .and_then(|mut addrs| {
                        addrs
                            .next()
                            .ok_or_else(|| std::io::ErrorKind::NotFound.into())
                    })
                    .and_then(|addr| TcpStream::connect_timeout(&addr, timeout))
                    .map_err(Refusal::Unreachable)
                    .and_then(|s| ask(s, &X11_SETUP, deadline, x11_reply))
            }
        };
        result.map_err(|refusal| refusal.words(self, timeout))
    }

    /// The protocol it speaks.
    fn protocol(&self) -> &'static str {
        match self {
            Display::Wayland(_) => "Wayland",
            Display::X11Local(_) | Display::X11Tcp(..) => "X11",
        }
    }
}

/// Why a display will not do.
#[derive(Debug)]
enum Refusal {
    /// The connection failed.
    Unreachable(std::io::Error),
    /// It took the request and said nothing within the time.
    Silent,
    /// It began to answer and stopped, short of a whole reply.
    Unfinished,
    /// It closed the connection without a whole reply.
    Closed,
    /// It answered something that is not its protocol.
    Garbled(String),
}

impl Refusal {
    /// The refusal in words, naming `display`.
    fn words(&self, display: &Display, timeout: Duration) -> String {
        let secs = timeout.as_secs();
        match self {
            Refusal::Unreachable(e) => format!(
                "the display {display} cannot be reached ({}: is its server gone?)",
                crate::files::io_words(e)
            ),
            Refusal::Silent => format!(
                "the display {display} accepted a connection but did not answer within {secs} s \
                 (is its server hung?)"
            ),
            Refusal::Unfinished => format!(
                "the display {display} began to answer but did not finish within {secs} s (is \
                 something other than {} listening there?)",
                display.protocol()
            ),
            Refusal::Closed => format!(
                "the display {display} closed the connection without answering (is its server \
                 shutting down?)"
            ),
            Refusal::Garbled(what) => format!(
                "the display {display} answered, but not in the {} protocol ({what}: is \
                 something else listening there?)",
                display.protocol()
            ),
        }
    }
}

impl std::fmt::Display for Display {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Display::Wayland(path) => {
                write!(f, "Wayland `{}`", crate::files::shown(path))
            }
            Display::X11Local(n) => write!(f, "X11 `:{n}` (/tmp/.X11-unix/X{n})"),
            Display::X11Tcp(host, n) => {
                write!(f, "X11 `{}:{n}`", crate::files::short_name(host))
            }
        }
    }
}

/// The longest reply read: an X server's set-up reply says its length in 16 bits of
/// 4-byte units; a Wayland message is at most 4 KiB.
const REPLY_CAP: usize = 8 + 4 * u16::MAX as usize;

/// Sends `request` on `stream` and reads its reply by `deadline` with `reply`, which asks
/// the stream for bytes as it reads the protocol's framing and says whether they are its.
fn ask<S: Read + Write + Timed>(
    mut stream: S,
    request: &[u8],
    deadline: Instant,
    reply: fn(&mut Reader<S>) -> Result<(), Refusal>,
) -> Result<(), Refusal> {
    let left = deadline.saturating_duration_since(Instant::now());
    if stream
        .set_timeouts(left.max(Duration::from_millis(1)))
        .is_err()
    {
        return Err(Refusal::Silent);
    }
    stream.write_all(request).map_err(|e| match e.kind() {
        std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut => Refusal::Silent,
        _ => Refusal::Closed,
    })?;
    reply(&mut Reader {
        stream,
        deadline,
        read: 0,
    })
}

/// A display's reply as it comes, read against a deadline.
struct Reader<S> {
    stream: S,
    deadline: Instant,
    /// Bytes read so far.
    read: usize,
}

impl<S: Read + Timed> Reader<S> {
    /// The next `n` bytes.
    fn take(&mut self, n: usize) -> Result<Vec<u8>, Refusal> {
        if self.read + n > REPLY_CAP {
            return Err(Refusal::Garbled(format!(
                "a reply of over {REPLY_CAP} bytes"
            )));
        }
        let mut buf = vec![0u8; n];
        let mut got = 0;
        while got < n {
            let left = self.deadline.saturating_duration_since(Instant::now());
            let timed_out = || match self.read + got {
                0 => Refusal::Silent,
                _ => Refusal::Unfinished,
            };
            if left.is_zero() || self.stream.set_timeouts(left).is_err() {
                return Err(timed_out());
            }
            match self.stream.read(&mut buf[got..]) {
                Ok(0) => return Err(Refusal::Closed),
                Ok(k) => got += k,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e)
                    if matches!(
                        e.kind(),
                        std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                    ) =>
                {
                    return Err(timed_out());
                }
                Err(_) => return Err(Refusal::Closed),
            }
        }
        self.read += n;
        Ok(buf)
    }
}

/// A little-endian u16 and u32 at `at`.
fn u16_at(b: &[u8], at: usize) -> usize {
    usize::from(u16::from_le_bytes([b[at], b[at + 1]]))
}
fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}

/// An X11 connection set-up, little-endian, protocol 11.0, no authorisation: the server
/// answers with success, failure or a request to authenticate, any of which will do.
const X11_SETUP: [u8; 12] = [b'l', 0, 11, 0, 0, 0, 0, 0, 0, 0, 0, 0];

/// Reads the X server's set-up reply: 8 bytes (status 0 failed, 1 success or 2
/// authenticate; the protocol's major version 11 after a failure or a success; the length
/// of what follows in 4-byte units), then all of what follows.
fn x11_reply<S: Read + Timed>(r: &mut Reader<S>) -> Result<(), Refusal> {
    let head = r.take(8)?;
    let (status, length) = (head[0], 4 * u16_at(&head, 6));
    let garbled = |what: String| Err(Refusal::Garbled(what));
    match status {
        0 | 1 if u16_at(&head, 2) != 11 => {
            return garbled(format!("protocol version {}, not 11", u16_at(&head, 2)));
        }
        // The reason's length, padded to 4 bytes, is what follows.
        0 if length != usize::from(head[1]).next_multiple_of(4) => {
            return garbled(format!("a refusal of {} bytes saying {length}", head[1]));
        }
        // A success's fixed part alone is 32 bytes.
        1 if length < 32 => return garbled(format!("a set-up of {length} bytes")),
        0..=2 => {}
        other => return garbled(format!("status {other}, not 0, 1 or 2")),
    }
    let rest = r.take(length)?;
    if status == 1 {
        // The vendor's name and the pixmap formats (8 bytes each) fit in the reply.
        let (vendor, formats) = (u16_at(&rest, 16), usize::from(rest[21]));
        if 32 + vendor.next_multiple_of(4) + 8 * formats > length {
            return garbled(format!(
                "a set-up of {length} bytes that does not hold its parts"
            ));
        }
    }
    Ok(())
}

/// Wayland's `wl_display.sync` (object 1, opcode 0, 12 bytes, new callback 2): the
/// compositor answers with the callback's `done`.
const WAYLAND_SYNC: [u8; 12] = [1, 0, 0, 0, 0, 0, 12, 0, 2, 0, 0, 0];

/// Reads the compositor's messages until the callback's `done` (object 2, opcode 0, 12
/// bytes) or the display's `error` (object 1, opcode 0): each a header of 8 bytes (object,
/// then size << 16 | opcode, the size a multiple of 4 from 8 to 4,096) and its body. The
/// display's `delete_id` (object 1, opcode 1, 12 bytes) may come between; nothing else can,
/// on a connection that has made no other object.
fn wayland_reply<S: Read + Timed>(r: &mut Reader<S>) -> Result<(), Refusal> {
    loop {
        let head = r.take(8)?;
        let (object, word) = (u32_at(&head, 0), u32_at(&head, 4));
        let (size, opcode) = ((word >> 16) as usize, word & 0xffff);
        if !(8..=4096).contains(&size) || size % 4 != 0 {
            return Err(Refusal::Garbled(format!("a message of {size} bytes")));
        }
        r.take(size - 8)?;
        match (object, opcode, size) {
            (2, 0, 12) | (1, 0, _) => return Ok(()),
            (1, 1, 12) => {}
            _ => {
                return Err(Refusal::Garbled(format!(
                    "event {opcode} of object {object}, {size} bytes"
                )));
            }
        }
    }
}

/// A stream whose reads and writes can time out.
trait Timed {
    fn set_timeouts(&self, timeout: Duration) -> std::io::Result<()>;
}

impl Timed for UnixStream {
    fn set_timeouts(&self, timeout: Duration) -> std::io::Result<()> {
        self.set_read_timeout(Some(timeout))?;
        self.set_write_timeout(Some(timeout))
    }
}

impl Timed for TcpStream {
    fn set_timeouts(&self, timeout: Duration) -> std::io::Result<()> {
        self.set_read_timeout(Some(timeout))?;
        self.set_write_timeout(Some(timeout))
    }
}

/// `Ok` if the display the environment names answers in its protocol within
/// [`ANSWER_WITHIN`] (or names none this check knows how to reach); else what is wrong with
/// it, in words that name it.
pub fn check() -> Result<(), String> {
    Display::from_env().map_or(Ok(()), |display| display.answers(ANSWER_WITHIN))
}

#[cfg(test)]
mod tests {
    use std::io::Write;
    use std::os::unix::net::UnixStream;
    use std::time::{Duration, Instant};

    use proptest::prelude::*;

    use super::{Display, Refusal, WAYLAND_SYNC, X11_SETUP, ask, wayland_reply, x11_reply};

    /// What a display that sends `bytes` and keeps the connection open (or closes it, if
    /// `close`) makes of the X11 or the Wayland request, within 300 ms.
    fn answer(x11: bool, bytes: &[u8], close: bool) -> Result<(), Refusal> {
        let (client, mut server) = UnixStream::pair().unwrap();
        server.write_all(bytes).unwrap();
        if close {
            drop(server.shutdown(std::net::Shutdown::Write));
        }
        let deadline = Instant::now() + Duration::from_millis(300);
        let result = match x11 {
            true => ask(client, &X11_SETUP, deadline, x11_reply),
            false => ask(client, &WAYLAND_SYNC, deadline, wayland_reply),
        };
        drop(server);
        result
    }

    /// An X server's set-up reply: `status`, the byte after it, version 11.0, and `rest`.
    fn x11(status: u8, second: u8, rest: &[u8]) -> Vec<u8> {
        let units = u16::try_from(rest.len() / 4).unwrap();
        let mut head = vec![status, second, 11, 0, 0, 0];
        head.extend(units.to_le_bytes());
        head.extend(rest);
        head
    }

    /// A success's fixed part (32 bytes) naming a vendor of `vendor` bytes and no formats,
    /// then the vendor's name padded.
    fn x11_success(vendor: &[u8]) -> Vec<u8> {
        let mut rest = vec![0u8; 32];
        rest[16..18].copy_from_slice(&u16::try_from(vendor.len()).unwrap().to_le_bytes());
        rest.extend(vendor);
        rest.resize(32 + vendor.len().next_multiple_of(4), 0);
        x11(1, 0, &rest)
    }

    /// A Wayland message.
    fn wayland(object: u32, opcode: u32, body: &[u8]) -> Vec<u8> {
        let size = u32::try_from(8 + body.len()).unwrap();
        let mut m = object.to_le_bytes().to_vec();
        m.extend((size << 16 | opcode).to_le_bytes());
        m.extend(body);
        m
    }

    #[test]
    fn the_protocols_replies_are_taken() {
        let reason = b"No protocol specified\n\0\0";
        for reply in [
            x11_success(b"The X.Org Foundation"),
            x11_success(b""),
            x11(0, 22, reason),
            x11(2, 0, b"MIT-MAGIC-COOKIE-1 wanted\0\0\0"),
        ] {
            assert!(answer(true, &reply, false).is_ok(), "{reply:?}");
        }
        let done = wayland(2, 0, &7u32.to_le_bytes());
        let deleted = wayland(1, 1, &2u32.to_le_bytes());
        let mut error = 3u32.to_le_bytes().to_vec();
        error.extend(1u32.to_le_bytes());
        error.extend(4u32.to_le_bytes());
        error.extend(b"bad\0");
        for reply in [
            done.clone(),
            [deleted, done].concat(),
            wayland(1, 0, &error),
        ] {
            assert!(answer(false, &reply, false).is_ok(), "{reply:?}");
        }
    }

    #[test]
    fn what_is_not_the_protocol_is_refused_in_words() {
        let http = b"HTTP/1.1 400 Bad Request\r\nContent-Length: 0\r\n\r\n".repeat(64);
        let ssh = b"SSH-2.0-OpenSSH_9.6\r\n";
        for x11 in [true, false] {
            for bytes in [&http[..], ssh] {
                let refusal = answer(x11, bytes, false).unwrap_err();
                assert!(
                    matches!(refusal, Refusal::Garbled(_) | Refusal::Unfinished),
                    "{refusal:?}"
                );
            }
            assert!(matches!(answer(x11, b"", false), Err(Refusal::Silent)));
            assert!(matches!(answer(x11, b"", true), Err(Refusal::Closed)));
        }
        // Framed like the protocol, but wrong in what it says.
        let mut v10 = x11_success(b"old");
        v10[2] = 10;
        let short = x11(1, 0, &[0u8; 8]);
        let failed_long = x11(0, 3, &[0u8; 16]);
        let mut no_room = x11_success(b"");
        no_room[8 + 21] = 200;
        for reply in [v10, short, failed_long, no_room] {
            let refusal = answer(true, &reply, false).unwrap_err();
            assert!(
                matches!(refusal, Refusal::Garbled(_)),
                "{reply:?}: {refusal:?}"
            );
        }
        for reply in [
            wayland(3, 0, &[0; 4]),
            wayland(2, 1, &[0; 4]),
            vec![1, 0, 0, 0, 0, 0, 5, 0],
        ] {
            let refusal = answer(false, &reply, false).unwrap_err();
            assert!(
                matches!(refusal, Refusal::Garbled(_)),
                "{reply:?}: {refusal:?}"
            );
        }
        // A reply cut short, the connection held open or closed.
        let cut = &x11_success(b"The X.Org Foundation")[..20];
        assert!(matches!(answer(true, cut, false), Err(Refusal::Unfinished)));
        assert!(matches!(answer(true, cut, true), Err(Refusal::Closed)));
        let words = Refusal::Garbled("status 72, not 0, 1 or 2".into())
            .words(&Display::X11Local(7), Duration::from_secs(5));
        assert!(
            words.contains("`:7`") && words.contains("not in the X11 protocol"),
            "{words}"
        );
    }

    proptest! {
        /// Whatever bytes a display sends, the answer comes by the deadline, and it is a
        /// refusal unless the bytes begin with what the protocol allows there (a status of
        /// 0, 1 or 2; an object of 1 or 2).
        #[test]
        fn any_bytes_are_answered_in_time(bytes in proptest::collection::vec(any::<u8>(), 0..4096), close: bool) {
            let x11 = answer(true, &bytes, close);
            prop_assert!(x11.is_err() || bytes[0] <= 2, "{:?}", x11);
            let wayland = answer(false, &bytes, close);
            prop_assert!(wayland.is_err() || matches!(bytes[0], 1 | 2), "{:?}", wayland);
        }
    }

    #[test]
    fn x11_names_are_read_as_xlib_reads_them() {
        assert_eq!(Display::x11(":0"), Some(Display::X11Local(0)));
        assert_eq!(Display::x11(":12.1"), Some(Display::X11Local(12)));
        assert_eq!(Display::x11("unix:3"), Some(Display::X11Local(3)));
        assert_eq!(
            Display::x11("remote.example:10.0"),
            Some(Display::X11Tcp("remote.example".into(), 10))
        );
        assert_eq!(Display::x11("/private/tmp/launch-x/org.x:0"), None);
        assert_eq!(Display::x11("nonsense"), None);
        assert_eq!(Display::x11(":x"), None);
    }
}
