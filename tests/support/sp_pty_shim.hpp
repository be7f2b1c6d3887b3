// A test-only shim that lets libserialport 0.1.1 open a pseudo-terminal, so the SpSerial backend
// can be tested without serial hardware. Linked only into test_serial_sp (never into a program).
//
// libserialport fails on a pty at two points (docs/protocol.md, "Transports"):
//  1. sp_get_port_by_name -> get_port_details (linux.c) lstat()s and readlink()s
//     /sys/class/tty/pts/N, which does not exist: SP_ERR_ARG "Device not found".
//  2. sp_open -> get_config (serialport.c) reads the modem lines with ioctl(TIOCMGET), and
//     set_config sets RTS/DTR with ioctl(TIOCMBIS/TIOCMBIC); the pty driver has no modem lines:
//     ENOTTY, SP_ERR_FAIL "TIOCMGET ioctl failed".
// The shim defines `__lxstat`, `lstat`, `readlink` and `ioctl` in the test executable. The dynamic
// linker binds libserialport's calls (through its PLT) to the executable's definitions first, so
// no LD_PRELOAD library is needed (which would have to come before AddressSanitizer's runtime).
// For a /sys/class/tty/pts/N path the lookups answer "a symlink to ../../devices/virtual/tty/pts/N";
// for TIOCMGET/TIOCMSET/TIOCMBIS/TIOCMBIC on a pty slave (character device, major 136-143) ioctl
// keeps a modem-line word per pty. Every other call goes to the next definition (AddressSanitizer's
// interceptor or the C library) unchanged.
#pragma once

namespace geojcbb::test::sp_pty_shim {

/// Switches each half of the shim (both on at start), to show what libserialport does without it.
void set_sysfs(bool on);
void set_modem_lines(bool on);

/// Calls the shim answered itself (not forwarded), since start.
struct Counts {
  long sysfs_lookups = 0;  ///< __lxstat/lstat/readlink of /sys/class/tty/pts/N
  long modem_get = 0;      ///< TIOCMGET on a pty slave
  long modem_set = 0;      ///< TIOCMSET/TIOCMBIS/TIOCMBIC on a pty slave
};
Counts counts();

/// The modem-line word the shim keeps for the pty at `path` (TIOCM_* bits; -1 if none yet).
int modem_lines(const char* path);

}  // namespace geojcbb::test::sp_pty_shim
