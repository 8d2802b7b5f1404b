#!/usr/bin/python3
"""A CANopen device written for the tests, independent of the gateway's stack
(python-can only): NMT slave (CiA 301 7.2.8.3.1), boot-up and heartbeat
(7.2.8.3.3, 7.2.8.3.2) and an SDO server (7.2.4.3) with expedited uploads and
expedited or segmented downloads. It is started before the gateway, as
devices are powered before the Linux that manages them.

Prints one line per request it serves ("sdo read 1018:02", "sdo write
1400:01 4 bytes", "nmt 0x01"), and "state operational" and the like.

Usage: powered_device.py IFACE NODE [--state preop|operational] [--heartbeat-ms N]
       [--serial 0x...] [--device-type 0x...] [--vendor 0x...] [--product 0x...] [--revision 0x...]
"""
import argparse
import struct
import sys
import threading
import time

import can

STATE_BYTE = {"preop": 0x7F, "operational": 0x05, "stopped": 0x04}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("iface")
    ap.add_argument("node", type=int)
    ap.add_argument("--state", default="preop", choices=["preop", "operational"])
    ap.add_argument("--heartbeat-ms", type=int, default=100)
    num = lambda s: int(s, 0)
    ap.add_argument("--device-type", type=num, default=0x000F0191)
    ap.add_argument("--vendor", type=num, default=0x000005A1)
    ap.add_argument("--product", type=num, default=0x00008822)
    ap.add_argument("--revision", type=num, default=0x00010003)
    ap.add_argument("--serial", type=num, default=0x00C0FFEE)
    a = ap.parse_args()
    node = a.node
    od = {
        (0x1000, 0): a.device_type,
        (0x1001, 0): 0,
        (0x1017, 0): a.heartbeat_ms,
        (0x1018, 0): 4,
        (0x1018, 1): a.vendor,
        (0x1018, 2): a.product,
        (0x1018, 3): a.revision,
        (0x1018, 4): a.serial,
    }
    # PDO parameters (1400h..1BFFh), as CiA 301 7.5.2.35-38 gives them by
    # default: the four predefined COB-IDs of each kind, the rest disabled.
    for k in range(8):
        for base, first in ((0x1400, 0x200), (0x1800, 0x180)):
            cob = first + 0x100 * k + node if k < 4 else 0x80000000
            od[(base + k, 0)] = 5 if base == 0x1800 else 2
            od[(base + k, 1)] = cob | (0x80000000 if k >= 4 else 0)
            od[(base + k, 2)] = 0xFF
            od[(base + k + 0x200, 0)] = 0
            for sub in range(1, 9):
                od[(base + k + 0x200, sub)] = 0
        for sub in (3, 5):
            od[(0x1800 + k, sub)] = 0
    bus = can.Bus(channel=a.iface, interface="socketcan")
    lock = threading.Lock()
    st = {"state": a.state, "segmented": None}

    def say(text):
        print(text, flush=True)

    def send(cob, data):
        bus.send(can.Message(arbitration_id=cob, data=bytes(data), is_extended_id=False))

    def boot_up():
        st["state"] = "preop"
        send(0x700 + node, [0x00])
        say("boot-up")

    def heartbeats():
        while True:
            time.sleep(od[(0x1017, 0)] / 1000.0 if od[(0x1017, 0)] else 0.1)
            if od[(0x1017, 0)]:
                with lock:
                    send(0x700 + node, [STATE_BYTE[st["state"]]])

    def abort(index, sub, code):
        send(0x580 + node, [0x80, index & 0xFF, index >> 8, sub] + list(struct.pack("<I", code)))

    def sdo(d):
        ccs = d[0] >> 5
        index, sub = d[1] | d[2] << 8, d[3]
        if st["state"] == "stopped":
            return  # no SDO in stopped (7.3.2.2, table 41)
        if ccs == 2:  # initiate upload
            key = (index, sub)
            if key not in od:
                say("sdo read %04X:%02X unknown" % key)
                return abort(index, sub, 0x06020000)
            say("sdo read %04X:%02X" % key)
            send(0x580 + node, [0x43, d[1], d[2], sub] + list(struct.pack("<I", od[key] & 0xFFFFFFFF)))
        elif ccs == 1:  # initiate download
            e, s = d[0] >> 1 & 1, d[0] & 1
            if e:
                n = 4 - (d[0] >> 2 & 3) if s else 4
                od[(index, sub)] = int.from_bytes(bytes(d[4:4 + n]), "little")
                say("sdo write %04X:%02X %d bytes" % (index, sub, n))
            else:
                st["segmented"] = {"index": index, "sub": sub, "data": b"", "toggle": 0}
            send(0x580 + node, [0x60, d[1], d[2], sub, 0, 0, 0, 0])
        elif ccs == 0:  # download segment
            seg = st["segmented"]
            if seg is None:
                return abort(0, 0, 0x05040001)
            t, n, c = d[0] >> 4 & 1, 7 - (d[0] >> 1 & 7), d[0] & 1
            if t != seg["toggle"]:
                st["segmented"] = None
                return abort(seg["index"], seg["sub"], 0x05030000)
            seg["data"] += bytes(d[1:1 + n])
            send(0x580 + node, [0x20 | t << 4, 0, 0, 0, 0, 0, 0, 0])
            seg["toggle"] ^= 1
            if c:
                say("sdo write %04X:%02X %d bytes" % (seg["index"], seg["sub"], len(seg["data"])))
                st["segmented"] = None
        elif ccs == 4:  # abort from the client
            st["segmented"] = None
        else:
            abort(index, sub, 0x05040001)

    def nmt(d):
        if d[1] not in (0, node):
            return
        say("nmt 0x%02X" % d[0])
        if d[0] == 0x01:
            st["state"] = "operational"
        elif d[0] == 0x02:
            st["state"] = "stopped"
        elif d[0] == 0x80:
            st["state"] = "preop"
        elif d[0] in (0x81, 0x82):
            boot_up()
        say("state " + st["state"])

    boot_up()
    if a.state == "operational":
        st["state"] = "operational"  # started by someone else before the test
    threading.Thread(target=heartbeats, daemon=True).start()
    say("ready")
    try:
        for msg in bus:
            if msg.is_extended_id or msg.is_remote_frame or msg.is_error_frame:
                continue
            with lock:
                if msg.arbitration_id == 0x000 and len(msg.data) == 2:
                    nmt(msg.data)
                elif msg.arbitration_id == 0x600 + node and len(msg.data) == 8:
                    sdo(msg.data)
    except KeyboardInterrupt:
        pass
    finally:
        bus.shutdown()


if __name__ == "__main__":
    sys.exit(main())
