//! Whether the display a window would open on answers. winit connects to the Wayland
//! compositor or the X server the environment names and waits for ever for one that accepts
//! the connection and says nothing; so first one request is sent there, which must be
//! answered within [`ANSWER_WITHIN`]: the program then says which display is silent
//! instead of hanging.

use std::io::{Read, Write};
use std::net::{TcpStream, ToSocketAddrs};
use std::os::unix::net::UnixStream;
use std::path::PathBuf;
use std::time::Duration;

/// How long a display has to answer.
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

    /// `Ok` if the display answers one request within `timeout`; an error naming it if it
    /// is silent. A display that refuses the connection is left to winit to report.
    pub fn answers(&self, timeout: Duration) -> Result<(), String> {
        let silent = || {
            format!(
                "the display {self} accepted a connection but did not answer within {} s: is its \
                 server hung? (leave out the window: `gpuwars demo` plays without one)",
                timeout.as_secs()
            )
        };
        let answered = match self {
            Display::Wayland(path) => match UnixStream::connect(path) {
                Ok(stream) => ask(stream, &WAYLAND_SYNC, timeout),
                Err(_) => return Ok(()),
            },
            Display::X11Local(n) => match UnixStream::connect(format!("/tmp/.X11-unix/X{n}")) {
                Ok(stream) => ask(stream, &X11_SETUP, timeout),
                Err(_) => return Ok(()),
            },
            Display::X11Tcp(host, n) => {
                let port = 6000u16.saturating_add(u16::try_from(*n).unwrap_or(u16::MAX));
                let Some(addr) = (host.as_str(), port)
                    .to_socket_addrs()
                    .ok()
                    .and_then(|mut a| a.next())
                else {
                    return Ok(());
                };
                match TcpStream::connect_timeout(&addr, timeout) {
                    Ok(stream) => ask(stream, &X11_SETUP, timeout),
                    Err(_) => return Ok(()),
                }
            }
        };
        answered.then_some(()).ok_or_else(silent)
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

/// An X11 connection set-up, little-endian, protocol 11.0, no authorisation: the server
/// answers with success, failure or a request to authenticate, any of which will do.
const X11_SETUP: [u8; 12] = [b'l', 0, 11, 0, 0, 0, 0, 0, 0, 0, 0, 0];

/// Wayland's `wl_display.sync` (object 1, opcode 0, 12 bytes, new callback 2): the
/// compositor answers with the callback's `done`.
const WAYLAND_SYNC: [u8; 12] = [1, 0, 0, 0, 0, 0, 12, 0, 2, 0, 0, 0];

/// Whether `request`, sent on `stream`, is answered (a byte, or the end of the stream)
/// within `timeout`.
fn ask(mut stream: impl Read + Write + Timed, request: &[u8], timeout: Duration) -> bool {
    if stream.set_timeouts(timeout).is_err() || stream.write_all(request).is_err() {
        // A socket that cannot take a request is not silent: winit reports it.
        return true;
    }
    let mut byte = [0u8; 1];
    // A byte, or the end of the stream (the display closed it): either way it answered.
    match stream.read(&mut byte) {
        Ok(0 | 1) => true,
        Ok(_) => unreachable!("a read into one byte"),
        Err(e) => !matches!(
            e.kind(),
            std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
        ),
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

/// `Ok` if the display the environment names answers within [`ANSWER_WITHIN`] (or names
/// none this check can reach); else the error that names it.
pub fn check() -> Result<(), String> {
    Display::from_env().map_or(Ok(()), |display| display.answers(ANSWER_WITHIN))
}

#[cfg(test)]
mod tests {
    use super::Display;

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
