"""Per-deployment keys of the authenticated links (ROS-free).

One key file per link (Touchball console: ``console.key``; SARAS arms: ``saras_arm.key``): one
line of 64 to 128 hexadecimal digits (a 32- to 64-byte key), optional ``#`` comment lines,
nothing else. The file must be a regular file that neither group nor others may access (mode
0600 or 0400); anything else is refused with a message naming the file
(``docs/touchball_protocol.md``, ``docs/security.md``). ``python3 -m saras_drivers.keys <path>``
writes a new random key file with mode 0600 (refuses to overwrite).
"""

import os
import secrets
import stat
import sys

MIN_KEY_BYTES = 32
MAX_KEY_BYTES = 64


class KeyFileError(ValueError):
    """A missing, unsafe or malformed key file; the message names the file."""


def parse_key_text(text):
    """The key (bytes) of a key file's text; raises ValueError on a malformed key."""
    lines = [ln.strip() for ln in text.splitlines()]
    keys = [ln for ln in lines if ln and not ln.startswith('#')]
    if len(keys) != 1:
        raise ValueError('expected exactly one key line, found %d' % len(keys))
    hexkey = keys[0]
    if len(hexkey) % 2 or not 2 * MIN_KEY_BYTES <= len(hexkey) <= 2 * MAX_KEY_BYTES:
        raise ValueError('the key must be one line of 64 to 128 hexadecimal digits (32 to 64 bytes)')
    try:
        return bytes.fromhex(hexkey)
    except ValueError:
        raise ValueError('the key holds a character that is not a hexadecimal digit')


def read_key_file(path):
    """Read and check a key file; raises :class:`KeyFileError` naming ``path``."""
    if not path:
        raise KeyFileError('no key file given (~key_file is empty)')
    try:
        st = os.stat(path)
    except OSError as e:
        raise KeyFileError('key file %s: %s' % (path, e.strerror))
    if not stat.S_ISREG(st.st_mode):
        raise KeyFileError('key file %s is not a regular file' % path)
    if st.st_mode & 0o077:
        raise KeyFileError('key file %s has mode %04o: group/others may access it; run chmod 600 %s'
                           % (path, stat.S_IMODE(st.st_mode), path))
    try:
        with open(path, 'r') as f:
            text = f.read()
    except (OSError, UnicodeDecodeError) as e:
        raise KeyFileError('key file %s: %s' % (path, e))
    try:
        return parse_key_text(text)
    except ValueError as e:
        raise KeyFileError('key file %s: %s' % (path, e))


def new_key(n=MIN_KEY_BYTES):
    return secrets.token_bytes(n)


def write_key_file(path, key=None):
    """Create ``path`` (mode 0600, must not exist) holding ``key`` (default: a new 32-byte key)."""
    key = new_key() if key is None else bytes(key)
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    with os.fdopen(fd, 'w') as f:
        f.write(key.hex() + '\n')
    return key


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) != 1:
        sys.stderr.write('usage: python3 -m saras_drivers.keys <new key file>\n')
        return 2
    try:
        write_key_file(argv[0])
    except OSError as e:
        sys.stderr.write('%s: %s\n' % (argv[0], e.strerror))
        return 1
    return 0


if __name__ == '__main__':
    sys.exit(main())
