#!/usr/bin/env python3
"""A second, independent pcapng reader (written from the pcapng draft,
draft-ietf-opsawg-pcapng, and the LINKTYPE_CAN_SOCKETCAN definition) that
checks a capture the gateway wrote and prints each frame in candump -L form
plus its direction, and an Interface Statistics Block's counts:

    (1700000000.123456) vcan0 123#DEADBEEF rx
    # vcan0: statistics dropped=0 received=42

Exits 1 with a reason on anything that is not well-formed: block lengths,
byte-order magic, link type, option layout, EPB lengths.

usage: pcapng_read.py FILE
"""
import struct
import sys


def fail(msg):
    print("pcapng_read: " + msg, file=sys.stderr)
    sys.exit(1)


def options(body, off, end, endian):
    out = {}
    while off + 4 <= end:
        code, length = struct.unpack_from(endian + "HH", body, off)
        off += 4
        if code == 0:
            return out
        out.setdefault(code, []).append(body[off:off + length])
        off += (length + 3) // 4 * 4
    fail("options without opt_endofopt")


def can_text(pkt, tsresol_div):
    if len(pkt) < 8:
        fail("SocketCAN packet shorter than 8 bytes")
    can_id, length, flags = struct.unpack_from(">IBB", pkt, 0)
    eff = bool(can_id & 0x80000000)
    rtr = bool(can_id & 0x40000000)
    ident = can_id & (0x1FFFFFFF if eff else 0x7FF)
    fd = bool(flags & 0x04) or len(pkt) == 72
    text = ("%08X" if eff else "%03X") % ident + "#"
    if rtr:
        text += "R" + ("%X" % length if length else "")
        return text
    if fd:
        text += "#%X" % (flags | 0x04)
    data = pkt[8:8 + length]
    if len(data) != length:
        fail("payload length %d beyond the packet" % length)
    return text + data.hex().upper()


def main(path):
    raw = open(path, "rb").read()
    off = 0
    endian = None
    interfaces = []
    lines = []
    while off < len(raw):
        if off + 12 > len(raw):
            fail("truncated block header at %d" % off)
        btype_le = struct.unpack_from("<I", raw, off)[0]
        if btype_le == 0x0A0D0D0A:
            magic = raw[off + 8:off + 12]
            if magic == b"\x4d\x3c\x2b\x1a":
                endian = "<"
            elif magic == b"\x1a\x2b\x3c\x4d":
                endian = ">"
            else:
                fail("bad byte-order magic")
            interfaces = []
        if endian is None:
            fail("first block is not a Section Header Block")
        btype, blen = struct.unpack_from(endian + "II", raw, off)
        if blen % 4 or blen < 12 or off + blen > len(raw):
            fail("bad block length %d at %d" % (blen, off))
        if struct.unpack_from(endian + "I", raw, off + blen - 4)[0] != blen:
            fail("trailing block length differs at %d" % off)
        body = raw[off + 8:off + blen - 4]
        if btype == 0x0A0D0D0A:
            major, minor = struct.unpack_from(endian + "HH", body, 4)
            if (major, minor) != (1, 0):
                fail("version %d.%d" % (major, minor))
            options(body, 16, len(body), endian)
        elif btype == 1:
            linktype, _, snaplen = struct.unpack_from(endian + "HHI", body, 0)
            if linktype != 227:
                fail("link type %d, not LINKTYPE_CAN_SOCKETCAN (227)" % linktype)
            opts = options(body, 8, len(body), endian)
            name = opts.get(2, [b"?"])[0].decode()
            res = opts.get(9, [b"\x06"])[0][0]
            div = 2 ** (res & 0x7F) if res & 0x80 else 10 ** res
            interfaces.append((name, div))
        elif btype == 6:
            iface, hi, lo, cap, orig = struct.unpack_from(endian + "IIIII", body, 0)
            if iface >= len(interfaces):
                fail("EPB for undeclared interface %d" % iface)
            if cap > orig:
                fail("captured length over original length")
            pkt = body[20:20 + cap]
            opts = options(body, 20 + (cap + 3) // 4 * 4, len(body), endian)
            direction = "?"
            if 2 in opts:
                fl = struct.unpack(endian + "I", opts[2][0])[0] & 3
                direction = {1: "rx", 2: "tx"}.get(fl, "?")
            name, div = interfaces[iface]
            ts = (hi << 32) | lo
            sec, frac = divmod(ts, div)
            usec = frac * 1000000 // div
            lines.append("(%010d.%06d) %s %s %s" % (sec, usec, name, can_text(pkt, div), direction))
        elif btype == 5:
            iface = struct.unpack_from(endian + "I", body, 0)[0]
            if iface >= len(interfaces):
                fail("ISB for undeclared interface %d" % iface)
            opts = options(body, 12, len(body), endian)
            count = {}
            for code, name in ((4, "received"), (5, "dropped")):
                if code in opts:
                    if len(opts[code][0]) != 8:
                        fail("ISB option %d is not 8 bytes" % code)
                    count[name] = struct.unpack(endian + "Q", opts[code][0])[0]
            lines.append("# %s: statistics %s" % (interfaces[iface][0], " ".join(
                "%s=%d" % (k, v) for k, v in sorted(count.items()))))
        off += blen
    print("\n".join(lines))


if __name__ == "__main__":
    if len(sys.argv) != 2:
        fail(__doc__)
    main(sys.argv[1])
