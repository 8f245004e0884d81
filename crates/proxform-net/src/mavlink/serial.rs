//! A serial line to an autopilot: a flight controller's TELEM port on a companion computer's
//! UART or USB (`serial:/dev/ttyAMA0:921600`). The device is opened raw (8 data bits, no
//! parity, no flow control, no echo, no line discipline) at one of the standard baud rates,
//! written whole frames and read with a timeout; framing the byte stream is the link's
//! ([`super::link`]). Linux only: elsewhere opening one says so.

use std::time::Duration;

/// The baud rates a serial endpoint may ask for.
pub const BAUDS: [u32; 15] = [
    9_600, 19_200, 38_400, 57_600, 115_200, 230_400, 460_800, 500_000, 576_000, 921_600, 1_000_000, 1_152_000,
    1_500_000, 2_000_000, 4_000_000,
];

/// An open serial line.
#[derive(Debug)]
pub struct SerialLine {
    #[cfg(target_os = "linux")]
    file: std::fs::File,
}

#[cfg(target_os = "linux")]
impl SerialLine {
    /// Opens `path` raw at `baud` (one of [`BAUDS`]).
    pub fn open(path: &str, baud: u32) -> std::io::Result<Self> {
        use nix::sys::termios::{self, BaudRate, ControlFlags, SetArg, SpecialCharacterIndices};
        use std::os::unix::fs::OpenOptionsExt;
        let rate = match baud {
            9_600 => BaudRate::B9600,
            19_200 => BaudRate::B19200,
            38_400 => BaudRate::B38400,
            57_600 => BaudRate::B57600,
            115_200 => BaudRate::B115200,
            230_400 => BaudRate::B230400,
            460_800 => BaudRate::B460800,
            500_000 => BaudRate::B500000,
            576_000 => BaudRate::B576000,
            921_600 => BaudRate::B921600,
            1_000_000 => BaudRate::B1000000,
            1_152_000 => BaudRate::B1152000,
            1_500_000 => BaudRate::B1500000,
            2_000_000 => BaudRate::B2000000,
            4_000_000 => BaudRate::B4000000,
            _ => {
                return Err(std::io::Error::new(
                    std::io::ErrorKind::InvalidInput,
                    format!("{baud} baud is not a standard rate ({BAUDS:?})"),
                ))
            }
        };
        // Not the process's controlling terminal: a line's hang-up must not end the agent.
        let file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .custom_flags(nix::fcntl::OFlag::O_NOCTTY.bits())
            .open(path)?;
        let mut t = termios::tcgetattr(&file)?;
        termios::cfmakeraw(&mut t);
        termios::cfsetspeed(&mut t, rate)?;
        t.control_flags |= ControlFlags::CLOCAL | ControlFlags::CREAD;
        t.control_flags &= !(ControlFlags::CRTSCTS | ControlFlags::CSTOPB);
        // Reads return what is there (the wait is poll's).
        t.control_chars[SpecialCharacterIndices::VMIN as usize] = 0;
        t.control_chars[SpecialCharacterIndices::VTIME as usize] = 0;
        termios::tcsetattr(&file, SetArg::TCSANOW, &t)?;
        Ok(Self { file })
    }

    /// Reads what arrived into `buf`, waiting at most `timeout` for something (0 bytes: nothing).
    pub fn read(&mut self, buf: &mut [u8], timeout: Duration) -> std::io::Result<usize> {
        use nix::poll::{poll, PollFd, PollFlags, PollTimeout};
        use std::io::Read;
        use std::os::fd::AsFd;
        let ms = u16::try_from(timeout.as_micros().div_ceil(1000)).unwrap_or(u16::MAX);
        let mut fds = [PollFd::new(self.file.as_fd(), PollFlags::POLLIN)];
        match poll(&mut fds, PollTimeout::from(ms)) {
            Ok(0) => return Ok(0),
            Ok(_) => {}
            Err(nix::errno::Errno::EINTR) => return Ok(0),
            Err(e) => return Err(e.into()),
        }
        match self.file.read(buf) {
            Ok(n) => Ok(n),
            Err(e) if matches!(e.kind(), std::io::ErrorKind::WouldBlock | std::io::ErrorKind::Interrupted) => Ok(0),
            Err(e) => Err(e),
        }
    }

    /// Writes `bytes` whole.
    pub fn write(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        use std::io::Write;
        self.file.write_all(bytes)
    }
}

#[cfg(not(target_os = "linux"))]
impl SerialLine {
    /// Serial lines are opened on Linux only.
    pub fn open(_path: &str, _baud: u32) -> std::io::Result<Self> {
        Err(std::io::Error::new(std::io::ErrorKind::Unsupported, "serial links are opened on Linux only"))
    }

    /// Never reached: no line opens here.
    pub fn read(&mut self, _buf: &mut [u8], _timeout: Duration) -> std::io::Result<usize> {
        Ok(0)
    }

    /// Never reached: no line opens here.
    pub fn write(&mut self, _bytes: &[u8]) -> std::io::Result<()> {
        Ok(())
    }
}
