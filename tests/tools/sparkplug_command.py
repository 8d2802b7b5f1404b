#!/usr/bin/python3
"""Writes a Sparkplug B NCMD/DCMD payload, as a host application sends it,
with code protoc generates from proto/sparkplug_b.proto (as
sparkplug_check.py does), for the tests to publish with `mosquitto_pub -f`.

  sparkplug_command.py OUT 'NAME=TYPE:VALUE'...

TYPE is a DataType name of the specification (Boolean, UInt8, Int16, Int64,
Float, String, ...); the payload has a timestamp (UTC ms) and no seq (facts
A.3, A.5). Example: sparkplug_command.py rebirth.bin 'Node Control/Rebirth=Boolean:true'
"""

import os
import sys
import tempfile
import time

sys.dont_write_bytecode = True  # no __pycache__ in the source tree
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sparkplug_check  # noqa: E402


def main(argv):
    if len(argv) < 3:
        print(__doc__, file=sys.stderr)
        return 3
    with tempfile.TemporaryDirectory(prefix="sparkplug-command-") as tmp:
        pb = sparkplug_check.generate_module(sparkplug_check.DEFAULT_PROTO, tmp)
        p = pb.Payload()
        p.timestamp = int(time.time() * 1000)
        for spec in argv[2:]:
            name, _, typed = spec.rpartition("=")
            tname, _, text = typed.partition(":")
            dt = pb.DataType.Value(tname)
            m = p.metrics.add()
            m.name = name
            m.datatype = dt
            m.timestamp = p.timestamp
            field = sparkplug_check.VALUE_FIELD[dt]
            if field == "boolean_value":
                value = {"true": True, "false": False}[text]
            elif field in ("int_value", "long_value"):
                # Negative: the two's complement of the type's width, as Tahu does (facts A.7).
                bits = sparkplug_check.WIDTH.get(dt, 64)
                value = int(text, 0) & ((1 << bits) - 1)
            elif field in ("float_value", "double_value"):
                value = float(text)
            elif field == "bytes_value":
                value = bytes.fromhex(text)
            else:
                value = text
            setattr(m, field, value)
        with open(argv[1], "wb") as f:
            f.write(p.SerializeToString())
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
