#!/usr/bin/python3
"""Sparkplug B 3.0 edge-node checker: a second implementation on the decoder side.

Decodes every message under spBv1.0/ with code that protoc generates at run
time from the project's proto/sparkplug_b.proto (Debian's python3-protobuf;
the gateway writes its payloads with its own hand-written writer) and checks
the specification's edge-node rules as the facts sheet states them
(../shared/ref/sparkplug-ascii-lss-facts.md section A; every finding names its
fact) and the contract's "Sparkplug B" section.

Input, one MQTT message per line, as `mosquitto_sub -F '%U %r %q %x %t'`
prints it (receive time, retain flag, QoS, payload in hex, topic):
  live      it runs mosquitto_sub itself (MQTT 5, --retain-as-published and
            a QoS 2 subscription, so retain and QoS are the publisher's),
            optionally recording the lines (--record) for a later offline run;
  --capture FILE  a recorded file ("-" for stdin); an unfinished last line is
            ignored, so a capture still being written can be checked.

Output: JSON lines on stdout: {"event": "violation", "rule", "fact", "line",
"topic", "message"} for each broken rule, {"event": "message", ...} per
decoded message with --decode, and a final {"event": "summary"}. A short
verdict goes to stderr.

Exit status: 0 every rule held and every expectation was met; 1 a rule was
broken; 2 the rules held but an expectation was not met (yet: a caller may
poll a growing capture until it is 0); 3 usage or environment error.
"""

import argparse
import importlib
import json
import os
import queue
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time

NAMESPACE = "spBv1.0"
SUB_FORMAT = "%U %r %q %x %t"
HERE = os.path.dirname(os.path.abspath(__file__))
DEFAULT_PROTO = os.path.normpath(os.path.join(HERE, "..", "..", "proto", "sparkplug_b.proto"))

# DataType values (facts A.7).
INT8, INT16, INT32, INT64, UINT8, UINT16, UINT32, UINT64 = 1, 2, 3, 4, 5, 6, 7, 8
FLOAT, DOUBLE, BOOLEAN, STRING, DATETIME, TEXT, UUID = 9, 10, 11, 12, 13, 14, 15
DATASET, BYTES, FILE, TEMPLATE = 16, 17, 18, 19
# The value field each datatype travels in (facts A.7 "Wire mapping", arrays
# in bytes_value), as Tahu Java and Ignition read them (contract: UInt32 in
# long_value, tahu issues 131 and 397).
VALUE_FIELD = {
    INT8: "int_value", INT16: "int_value", INT32: "int_value",
    UINT8: "int_value", UINT16: "int_value", UINT32: "long_value",
    INT64: "long_value", UINT64: "long_value", DATETIME: "long_value",
    FLOAT: "float_value", DOUBLE: "double_value", BOOLEAN: "boolean_value",
    STRING: "string_value", TEXT: "string_value", UUID: "string_value",
    DATASET: "dataset_value", BYTES: "bytes_value", FILE: "bytes_value", TEMPLATE: "template_value",
}
VALUE_FIELD.update({t: "bytes_value" for t in range(22, 35)})
WIDTH = {INT8: 8, INT16: 16, INT32: 32, UINT8: 8, UINT16: 16, UINT32: 32}

# Device metrics of the contract that are not CANopen objects; every other
# DBIRTH metric is an object metric and carries index/subIndex.
NON_OBJECT_DEVICE_METRICS = {"Node/State", "EMCY/Error Code", "EMCY/Error Register", "EMCY/Description",
                             "Device Control/Rebirth"}

NODE_TYPES = {"NBIRTH", "NDEATH", "NDATA", "NCMD"}
DEVICE_TYPES = {"DBIRTH", "DDEATH", "DDATA", "DCMD"}
SEQ_TYPES = {"NBIRTH", "DBIRTH", "NDATA", "DDATA", "DDEATH"}

# Rule id -> the fact (or contract section) it comes from.
FACTS = {
    "decode": "A.7",            # the payload is a Sparkplug B Payload
    "topic": "A.2",             # namespace/group/type/edge[/device]
    "qos-retain": "A.3",        # NDEATH QoS 1, others QoS 0, none retained (STATE: QoS 1, retained)
    "timestamp": "A.3/A.7",     # payload and metric timestamps present
    "clock": "A.4.8",           # UTC milliseconds since 1970
    "seq": "A.5",               # previous + 1 mod 256; none on NDEATH, NCMD, DCMD
    "nbirth-seq": "A.5",        # NBIRTH seq 0 (also on rebirths)
    "bdseq-metric": "A.3/A.5",  # NBIRTH/NDEATH carry bdSeq, Int64, in long_value
    "rebirth-metric": "A.6",    # NBIRTH carries Node Control/Rebirth, Boolean false, no alias
    "birth-order": "A.3/A.4.4",  # NBIRTH first, DBIRTH before the device's DDATA/DDEATH
    "rebirth": "A.6",           # after a rebirth NBIRTH, every live device's DBIRTH before any DATA
    "metric": "A.3/A.7",        # birth metrics: name, datatype, value; names unique
    "value-type": "A.7",        # the value is in the field the datatype says
    "properties": "contract Sparkplug B",  # object metrics: index UInt16, subIndex UInt8
    "alias": "A.6/A.7",         # aliases unique over the edge node, DATA alias only, Rebirth unaliased
    "unknown-metric": "A.6/A.7",  # DATA metrics were born
    "ndeath": "A.3",            # NDEATH carries only bdSeq
    "ndeath-bdseq": "A.5",      # NDEATH's bdSeq is the one of the NBIRTH it ends
    "bdseq-sequence": "A.5",    # +1 per CONNECT, same on a rebirth
    "command": "A.3/A.5",       # NCMD/DCMD: timestamp, no seq
    "state": "A.8",             # STATE: JSON {"online", "timestamp"}
    "expect": "checker option",
}


def generate_module(proto_path, workdir):
    """sparkplug_b_pb2 from the project's .proto, generated into workdir."""
    protoc = shutil.which("protoc")
    if not protoc:
        raise RuntimeError("protoc not found (Debian package protobuf-compiler)")
    proto_dir, proto_file = os.path.split(os.path.abspath(proto_path))
    subprocess.run([protoc, "-I", proto_dir, "--python_out", workdir, proto_file], check=True)
    sys.path.insert(0, workdir)
    try:
        return importlib.import_module(os.path.splitext(proto_file)[0] + "_pb2")
    finally:
        sys.path.remove(workdir)


def metric_value(m, datatype=None):
    """The value as Python sees it: None for null, else the set oneof field,
    signed types from their two's complement (facts A.7). datatype: the
    born one, for DATA metrics (which carry none)."""
    datatype = m.datatype if datatype is None else datatype
    if m.HasField("is_null") and m.is_null:
        return None
    field = m.WhichOneof("value")
    if field is None:
        return None
    v = getattr(m, field)
    if field == "int_value" and datatype in (INT8, INT16, INT32):
        w = WIDTH[datatype]
        v &= (1 << w) - 1
        if v >= 1 << (w - 1):
            v -= 1 << w
    elif field == "long_value" and datatype == INT64 and v >= 1 << 63:
        v -= 1 << 64
    elif field == "bytes_value":
        v = v.hex()
    elif field in ("dataset_value", "template_value", "extension_value"):
        v = "<%s>" % field
    return v


def value_text(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if v is None:
        return "null"
    return str(v)


def value_matches(v, want):
    if value_text(v) == want:
        return True
    if isinstance(v, float):
        try:
            return abs(v - float(want)) <= 1e-6 * max(1.0, abs(v))
        except ValueError:
            return False
    return False


class EdgeState:
    """What the checker knows about one edge node (group/edge)."""

    def __init__(self):
        self.born = False            # an NBIRTH opened the current session and no NDEATH since
        self.bd_seq = None           # bdSeq of the current session's NBIRTH
        self.last_session_bd = None  # bdSeq of the latest session (for +1 on the next CONNECT)
        self.ended_bd = set()        # bdSeqs whose session an NDEATH already ended
        self.seq = None              # seq of the latest message of the session
        self.node_metrics = {}       # name -> datatype
        self.node_aliases = {}       # alias -> name
        self.devices = {}            # device id -> {"names": {name: dt}, "aliases": {alias: name}}
        self.alive = set()           # devices born in this session and not dead since
        self.pending = set()         # devices still to be reborn after a rebirth NBIRTH
        self.aliases = {}            # alias -> (device or "", name), over the whole edge node


class Checker:
    def __init__(self, pb, args):
        self.pb = pb
        self.args = args
        self.edges = {}
        self.violations = []
        self.messages = 0
        self.line_no = 0
        self.counts = {}             # message type -> count (from --from-line on)
        self.dbirth_devices = set()  # devices with a DBIRTH (from --from-line on)
        self.birth_metrics = set()   # (device, name) seen in a DBIRTH (from --from-line on)
        self.data_seen = []          # (device, name, value) of DDATA metrics (from --from-line on)
        self.sessions = {}           # "G/E" -> [bdSeq of each NBIRTH that opened a session]
        self.objects = {}            # (device, (index, subIndex)) -> (name, datatype, value), latest DBIRTH
        self.out = sys.stdout

    # ---- reporting -------------------------------------------------------
    def emit(self, obj):
        self.out.write(json.dumps(obj, sort_keys=False) + "\n")
        self.out.flush()

    def violation(self, rule, topic, message):
        v = {"event": "violation", "rule": rule, "fact": FACTS[rule], "line": self.line_no, "topic": topic,
             "message": message}
        self.violations.append(v)
        self.emit(v)

    # ---- input -----------------------------------------------------------
    def feed_line(self, line):
        """One line of `mosquitto_sub -F '%U %r %q %x %t'`."""
        self.line_no += 1
        line = line.rstrip("\n")
        if not line.strip():
            return
        parts = line.split(" ", 4)
        if len(parts) != 5:
            raise ValueError("line %d: not '<time> <retain> <qos> <hex> <topic>': %r" % (self.line_no, line[:80]))
        recv, retain, qos, hexpayload, topic = parts
        if not topic.startswith(NAMESPACE + "/"):
            return  # the checker's own readiness probe, or anything else
        self.message(topic, bytes.fromhex(hexpayload), int(qos), retain == "1", float(recv))

    # ---- one message -------------------------------------------------------
    def message(self, topic, payload, qos, retain, recv_time):
        self.messages += 1
        levels = topic.split("/")
        if len(levels) == 3 and levels[1] == "STATE":
            return self.state_message(topic, payload, qos, retain)
        if len(levels) < 4:
            return self.violation("topic", topic, "not spBv1.0/<group>/<type>/<edge>[/<device>]")
        group, mtype, edge = levels[1], levels[2], levels[3]
        device = "/".join(levels[4:]) if len(levels) > 4 else None
        if mtype not in NODE_TYPES | DEVICE_TYPES:
            return self.violation("topic", topic, "unknown message type %r" % mtype)
        if mtype in NODE_TYPES and device is not None:
            return self.violation("topic", topic, "%s has no device id level" % mtype)
        if mtype in DEVICE_TYPES and (device is None or not device or "/" in device):
            return self.violation("topic", topic, "%s needs exactly one device id level" % mtype)
        for part in (group, edge, device or "x"):
            if not part or any(c in part for c in "+#"):
                return self.violation("topic", topic, "empty id or '+'/'#' in an id")
        if self.args.group and group != self.args.group:
            return
        if self.args.edge and edge != self.args.edge:
            return

        p = self.pb.Payload()
        try:
            p.ParseFromString(payload)
        except Exception as e:  # noqa: BLE001 - any parse error is the finding
            return self.violation("decode", topic, "not a Sparkplug B Payload (%s)" % e)

        counting = self.line_no > self.args.from_line
        if counting:
            self.counts[mtype] = self.counts.get(mtype, 0) + 1
        self.born_types = {}  # DATA metric's position -> (born name, born datatype), filled by data()
        self.check(topic, group, mtype, edge, device, p, qos, retain, recv_time, counting)
        if self.args.decode:  # after the checks: DATA values typed as their birth says
            self.emit(self.describe(topic, mtype, device, p, qos, retain))

    def check(self, topic, group, mtype, edge, device, p, qos, retain, recv_time, counting):
        # QoS and retain per message type (facts A.3).
        want_qos = 1 if mtype == "NDEATH" else 0
        if qos != want_qos or retain:
            self.violation("qos-retain", topic, "%s came with QoS %d retain %d; the publisher must use QoS %d, "
                           "not retained" % (mtype, qos, int(retain), want_qos))

        key = group + "/" + edge
        st = self.edges.setdefault(key, EdgeState())
        if mtype in ("NCMD", "DCMD"):
            return self.command(topic, p)
        if mtype == "NDEATH":
            return self.ndeath(topic, st, key, p)

        # Every other edge-node message: timestamp and seq.
        if not p.HasField("timestamp"):
            self.violation("timestamp", topic, "%s without a payload timestamp" % mtype)
        elif not self.args.no_clock and abs(p.timestamp / 1000.0 - recv_time) > self.args.max_skew:
            self.violation("clock", topic, "payload timestamp %d is %.0f s from the time it arrived; not UTC ms?"
                           % (p.timestamp, p.timestamp / 1000.0 - recv_time))
        if mtype == "NBIRTH":
            self.nbirth(topic, st, key, p)
        elif not st.born:
            if self.args.allow_late_start and st.bd_seq is None and st.last_session_bd is None:
                return  # joined an edge node's running session: wait for its NBIRTH
            return self.violation("birth-order", topic, "%s before the edge node's NBIRTH" % mtype)
        else:
            self.check_seq(topic, st, p)
        if mtype == "DBIRTH":
            self.dbirth(topic, st, device, p, counting)
        elif mtype == "DDEATH":
            if device not in st.alive:
                self.violation("birth-order", topic, "DDEATH of %s without its DBIRTH in this session" % device)
            st.alive.discard(device)
            st.pending.discard(device)
            if p.metrics:
                self.violation("metric", topic, "DDEATH carries metrics")
        elif mtype in ("NDATA", "DDATA"):
            if st.pending:
                self.violation("rebirth", topic, "%s before the DBIRTH of %s after a rebirth"
                               % (mtype, ", ".join(sorted(st.pending))))
            if mtype == "DDATA" and device not in st.alive:
                return self.violation("birth-order", topic, "DDATA of %s without its DBIRTH in this session"
                                      % device)
            self.data(topic, st, device, p, counting)

    # ---- per type --------------------------------------------------------
    def nbirth(self, topic, st, key, p):
        if not p.HasField("seq"):
            self.violation("seq", topic, "NBIRTH without seq")
        elif p.seq != 0:
            self.violation("nbirth-seq", topic, "NBIRTH seq %d; it must be 0, on rebirths too" % p.seq)
        st.seq = p.seq if p.HasField("seq") else None
        names = self.birth_metrics_check(topic, p, device=None)
        bd = self.bdseq_of(topic, p, "NBIRTH")
        reb = [m for m in p.metrics if m.name == "Node Control/Rebirth"]
        if not reb:
            self.violation("rebirth-metric", topic, "NBIRTH without the metric 'Node Control/Rebirth'")
        else:
            m = reb[0]
            if m.datatype != BOOLEAN or m.WhichOneof("value") != "boolean_value" or m.boolean_value:
                self.violation("rebirth-metric", topic, "'Node Control/Rebirth' must be Boolean false")
            if m.HasField("alias"):
                self.violation("alias", topic, "'Node Control/Rebirth' must never have an alias")
        if st.born:
            # A second NBIRTH in the same session: a rebirth (same bdSeq), and
            # every live device's DBIRTH before any DATA.
            if bd is not None and st.bd_seq is not None and bd != st.bd_seq:
                self.violation("bdseq-sequence", topic, "NBIRTH with bdSeq %d while the session of bdSeq %d has "
                               "no NDEATH: a rebirth keeps the bdSeq, a new CONNECT ends with an NDEATH (Will)"
                               % (bd, st.bd_seq))
            st.pending = set(st.alive)
        else:
            if bd is not None and st.last_session_bd is not None:
                want = (st.last_session_bd + 1) % 256
                if bd != want and not (self.args.allow_bdseq_skips and bd != st.last_session_bd):
                    self.violation("bdseq-sequence", topic, "NBIRTH of a new session with bdSeq %d; the previous "
                                   "session had %d, so %d was due (+1 per CONNECT)" % (bd, st.last_session_bd, want))
            st.pending = set()
            self.sessions.setdefault(key, []).append(bd)
        st.born = True
        st.bd_seq = bd
        if bd is not None:
            st.last_session_bd = bd
        st.alive = set()
        st.devices = {}
        st.aliases = {}
        st.node_metrics = names["names"]
        st.node_aliases = names["aliases"]
        self.register_aliases(topic, st, "", names["aliases"])
        if self.line_no > self.args.from_line:
            self.birth_metrics.update(("", n) for n in names["names"])

    def dbirth(self, topic, st, device, p, counting):
        names = self.birth_metrics_check(topic, p, device=device)
        # A DBIRTH of a live device (Device Control/Rebirth, or its metric set
        # changed) replaces its metrics and aliases.
        for alias in st.devices.get(device, {}).get("aliases", {}):
            st.aliases.pop(alias, None)
        st.devices[device] = names
        self.register_aliases(topic, st, device, names["aliases"])
        st.alive.add(device)
        st.pending.discard(device)
        if counting:
            self.dbirth_devices.add(device)
            self.birth_metrics.update((device, n) for n in names["names"])

    def ndeath(self, topic, st, key, p):
        if p.HasField("seq"):
            self.violation("seq", topic, "NDEATH must not carry seq")
        bd = self.bdseq_of(topic, p, "NDEATH")
        others = [m.name or str(m.alias) for m in p.metrics if m.name != "bdSeq"]
        if others:
            self.violation("ndeath", topic, "NDEATH carries more than bdSeq: %s" % ", ".join(others))
        if bd is None:
            pass
        elif st.born:
            if bd != st.bd_seq:
                self.violation("ndeath-bdseq", topic, "NDEATH with bdSeq %d ends the session born with bdSeq %s"
                               % (bd, st.bd_seq))
            st.ended_bd.add(bd)
        elif bd in st.ended_bd:
            pass  # the Will after an explicit NDEATH of the same session (MQTT 5 reason 0x04): a duplicate
        elif st.last_session_bd is not None and bd != st.last_session_bd and bd != (st.last_session_bd + 1) % 256:
            self.violation("ndeath-bdseq", topic, "NDEATH with bdSeq %d: the latest session had %d"
                           % (bd, st.last_session_bd))
        # An NDEATH without a session in this capture: a CONNECT that never
        # got to its NBIRTH (a Primary Host that is offline), nothing to pair.
        st.born = False
        st.alive = set()
        st.pending = set()
        st.seq = None

    def command(self, topic, p):
        if p.HasField("seq"):
            self.violation("command", topic, "NCMD/DCMD must not carry seq")
        if not p.HasField("timestamp"):
            self.violation("command", topic, "NCMD/DCMD without a payload timestamp")

    def state_message(self, topic, payload, qos, retain):
        try:
            obj = json.loads(payload.decode("utf-8"))
            ok = isinstance(obj, dict) and isinstance(obj.get("online"), bool) and isinstance(obj.get("timestamp"), int)
        except (ValueError, UnicodeDecodeError):
            ok = False
        if not ok:
            self.violation("state", topic, 'STATE payload is not {"online": <bool>, "timestamp": <UTC ms>}')
        if qos != 1 or not retain:
            self.violation("qos-retain", topic, "STATE came with QoS %d retain %d; it must be QoS 1, retained"
                           % (qos, int(retain)))

    # ---- pieces ----------------------------------------------------------
    def check_seq(self, topic, st, p):
        if not p.HasField("seq"):
            self.violation("seq", topic, "no seq")
            st.seq = None
            return
        if p.seq > 255:
            self.violation("seq", topic, "seq %d is beyond 255" % p.seq)
        if st.seq is not None and p.seq != (st.seq + 1) % 256:
            self.violation("seq", topic, "seq %d after %d; %d was due" % (p.seq, st.seq, (st.seq + 1) % 256))
        st.seq = p.seq

    def bdseq_of(self, topic, p, mtype):
        ms = [m for m in p.metrics if m.name == "bdSeq"]
        if not ms:
            self.violation("bdseq-metric", topic, "%s without the metric bdSeq" % mtype)
            return None
        m = ms[0]
        if m.datatype != INT64 or m.WhichOneof("value") != "long_value":
            self.violation("bdseq-metric", topic, "%s bdSeq must be Int64 (datatype 4) in long_value" % mtype)
            return None
        if m.long_value > 255:
            self.violation("bdseq-metric", topic, "%s bdSeq %d is beyond 255" % (mtype, m.long_value))
        return m.long_value

    def birth_metrics_check(self, topic, p, device):
        names, aliases = {}, {}
        for m in p.metrics:
            label = m.name or "alias %d" % m.alias
            if not m.name:
                self.violation("metric", topic, "birth metric without a name (%s)" % label)
                continue
            if m.name in names:
                self.violation("metric", topic, "metric name %r twice in one birth" % m.name)
            if not m.HasField("datatype") or m.datatype == 0:
                self.violation("metric", topic, "birth metric %r without a datatype" % m.name)
            if not m.HasField("timestamp"):
                self.violation("timestamp", topic, "birth metric %r without a timestamp" % m.name)
            self.check_value(topic, m, m.datatype, label, birth=True)
            if m.HasField("alias"):
                if m.alias in aliases:
                    self.violation("alias", topic, "alias %d twice in one birth" % m.alias)
                aliases[m.alias] = m.name
            names[m.name] = m.datatype
            if device is not None:
                obj = self.check_properties(topic, m)
                if obj is not None:
                    self.objects[(device, obj)] = (m.name, m.datatype, metric_value(m))
        return {"names": names, "aliases": aliases}

    def check_value(self, topic, m, datatype, label, birth):
        null = m.HasField("is_null") and m.is_null
        field = m.WhichOneof("value")
        if null:
            if field is not None:
                self.violation("value-type", topic, "%s is_null with a value" % label)
            return
        if field is None:
            self.violation("metric" if birth else "value-type", topic, "%s has no value and is not null" % label)
            return
        want = VALUE_FIELD.get(datatype)
        if want is not None and field != want:
            self.violation("value-type", topic, "%s: datatype %d travels in %s, not %s" % (label, datatype, want, field))
        elif datatype in (UINT8, UINT16) and m.int_value >= 1 << WIDTH[datatype]:
            self.violation("value-type", topic, "%s: %d does not fit datatype %d" % (label, m.int_value, datatype))
        elif datatype in (INT8, INT16) and (1 << (WIDTH[datatype] - 1)) <= m.int_value < (1 << 32) - (1 << (WIDTH[datatype] - 1)):
            # Contract: negative Int8/Int16 sign-extended to 32 bits (Tahu
            # Java); the two's complement of their own width reads as a
            # large positive number in Tahu JS.
            self.violation("value-type", topic, "%s: %d is not an Int%d sign-extended to 32 bits"
                           % (label, m.int_value, WIDTH[datatype]))
        elif datatype == UINT32 and m.long_value >= 1 << 32:
            self.violation("value-type", topic, "%s: %d does not fit datatype %d" % (label, m.long_value, datatype))

    def check_properties(self, topic, m):
        """Checks a device metric's properties; returns its (index, subIndex) if it has them."""
        keys = list(m.properties.keys)
        vals = list(m.properties.values)
        if len(keys) != len(vals):
            self.violation("properties", topic, "%r: %d property keys for %d values" % (m.name, len(keys), len(vals)))
            return
        props = dict(zip(keys, vals))
        is_object = m.name not in NON_OBJECT_DEVICE_METRICS or "index" in props or "subIndex" in props
        q = props.get("Quality")
        if q is not None and q.type != INT32:
            self.violation("properties", topic, "%r: property Quality must be Int32 (facts A.7)" % m.name)
        if not is_object:
            return None
        address = []
        for key, want_type, limit in (("index", UINT16, 0xFFFF), ("subIndex", UINT8, 0xFF)):
            v = props.get(key)
            if v is None:
                self.violation("properties", topic, "object metric %r without the property %r" % (m.name, key))
            elif v.type != want_type or v.WhichOneof("value") != "int_value" or v.int_value > limit:
                self.violation("properties", topic, "object metric %r: property %r must be datatype %d in int_value"
                               % (m.name, key, want_type))
            else:
                address.append(v.int_value)
        return tuple(address) if len(address) == 2 else None

    def register_aliases(self, topic, st, device, aliases):
        for alias, name in aliases.items():
            owner = st.aliases.get(alias)
            if owner is not None and owner != (device, name):
                self.violation("alias", topic, "alias %d of %r is already %s/%r; aliases are unique over the whole "
                               "edge node" % (alias, name, owner[0] or "(node)", owner[1]))
            st.aliases[alias] = (device, name)

    def data(self, topic, st, device, p, counting):
        if device is None:
            known, known_aliases = st.node_metrics, st.node_aliases
        else:
            d = st.devices[device]
            known, known_aliases = d["names"], d["aliases"]
        for pos, m in enumerate(p.metrics):
            if m.HasField("alias"):
                name = known_aliases.get(m.alias)
                if name is None:
                    self.violation("unknown-metric", topic, "alias %d was not born" % m.alias)
                    continue
                if m.name:
                    self.violation("alias", topic, "%r: DATA of an aliased metric carries the alias only" % m.name)
            else:
                name = m.name
                if name not in known:
                    self.violation("unknown-metric", topic, "metric %r was not born" % name)
                    continue
                if name in known_aliases.values():
                    self.violation("alias", topic, "%r was born with an alias; DATA carries the alias only" % name)
            if not m.HasField("timestamp"):
                self.violation("timestamp", topic, "DATA metric %r without a timestamp" % name)
            elif not self.args.no_clock and p.HasField("timestamp") and abs(int(m.timestamp) - int(p.timestamp)) > \
                    self.args.max_skew * 1000:
                self.violation("clock", topic, "metric %r timestamp %d is far from the payload's %d"
                               % (name, m.timestamp, p.timestamp))
            dt = known[name]
            if m.HasField("datatype") and m.datatype != dt:
                self.violation("value-type", topic, "%r born as datatype %d, DATA says %d" % (name, dt, m.datatype))
            self.check_value(topic, m, dt, repr(name), birth=False)
            self.born_types[pos] = (name, dt)
            if counting:
                self.data_seen.append((device or "", name, metric_value(m, dt)))

    def describe(self, topic, mtype, device, p, qos, retain):
        d = {"event": "message", "line": self.line_no, "type": mtype, "topic": topic, "qos": qos,
             "retain": retain}
        if device is not None:
            d["device"] = device
        if p.HasField("timestamp"):
            d["timestamp"] = p.timestamp
        if p.HasField("seq"):
            d["seq"] = p.seq
        d["metrics"] = [{k: v for k, v in (("name", m.name if m.HasField("name") else None),
                                           ("alias", m.alias if m.HasField("alias") else None),
                                           ("datatype", m.datatype if m.HasField("datatype") else None),
                                           ("value", metric_value(m, self.born_types.get(pos, (0, None))[1])))
                         if v is not None or k == "value"} for pos, m in enumerate(p.metrics)]
        for pos, out in enumerate(d["metrics"]):
            if pos in self.born_types and "name" not in out:
                out["born_name"] = self.born_types[pos][0]  # an aliased DATA metric's name, from its birth
        for m, out in zip(p.metrics, d["metrics"]):
            for key, v in zip(m.properties.keys, m.properties.values):
                if key in ("index", "subIndex") and v.WhichOneof("value") == "int_value":
                    out[key] = v.int_value
        return d

    # ---- expectations ----------------------------------------------------
    def unmet(self):
        a, c, out = self.args, self.counts, []
        for mtype, n in (("NBIRTH", a.min_nbirths), ("DBIRTH", a.min_dbirths), ("DDATA", a.min_ddata),
                         ("NDEATH", a.min_ndeaths), ("DDEATH", a.min_ddeaths)):
            if c.get(mtype, 0) < n:
                out.append("%d %s, %d expected" % (c.get(mtype, 0), mtype, n))
        for dev in a.expect_dbirth:
            if dev not in self.dbirth_devices:
                out.append("no DBIRTH of %s" % dev)
        for spec in a.expect_birth_metric:
            dev, _, name = spec.partition("/")
            if (dev, name) not in self.birth_metrics:
                out.append("no %s with metric %r" % ("DBIRTH of " + dev if dev else "NBIRTH", name))
        for spec in a.expect_birth_object:
            address, eq, want = spec.partition("=")
            dev, obj = parse_object(address)
            born = self.objects.get((dev, obj))
            if born is None or (eq and not value_matches(born[2], want)):
                out.append("no DBIRTH of %s with a metric for %04Xh:%d%s%s" % (
                    dev, obj[0], obj[1], " = " + want if eq else "",
                    " (it has %s)" % value_text(born[2]) if born is not None else ""))
        specs = [(spec, spec.partition("/")[0], spec.partition("/")[2]) for spec in a.expect_data]
        for spec in a.expect_data_object:
            dev, obj = parse_object(spec.partition("=")[0])
            name = self.objects.get((dev, obj), ("%04Xh:%d (not born)" % obj,))[0]
            specs.append((spec, dev, name + spec[len(spec.partition("=")[0]):]))
        for spec, dev, rest in specs:
            name, eq, want = rest.rpartition("=") if "=" in rest else (rest, "", "")
            if not any(d == dev and n == name and (not eq or value_matches(v, want)) for d, n, v in self.data_seen):
                out.append("no %s with %r%s (%s)" % ("DDATA of " + dev if dev else "NDATA", name,
                                                     "=" + want if eq else "", spec))
        return out

    def lookup(self, spec):
        """'NAME=TYPE' of the metric born for DEVICE/INDEXh:SUB, or None."""
        found = self.objects.get(parse_object(spec))
        return None if found is None else "%s=%s" % (found[0], self.pb.DataType.Name(found[1]))

    def summary(self):
        unmet = self.unmet()
        s = {"event": "summary", "ok": not self.violations and not unmet, "lines": self.line_no,
             "messages": self.messages, "violations": len(self.violations),
             "rules_broken": sorted({v["rule"] for v in self.violations}), "unmet": unmet, "counts": self.counts,
             "sessions": self.sessions, "devices": sorted(self.dbirth_devices)}
        self.emit(s)
        return s


def parse_object(spec):
    """'DEVICE/6200h:1' (or 0x6200:1) -> (device, (0x6200, 1))."""
    dev, _, obj = spec.rpartition("/")
    index, _, sub = obj.partition(":")
    index = int(index[:-1], 16) if index.lower().endswith("h") else int(index, 0)
    return dev, (index, int(sub or "0", 0))


# ---- running -------------------------------------------------------------
def run_capture(chk, path):
    f = sys.stdin if path == "-" else open(path, encoding="utf-8", errors="replace")
    with f:
        for line in f:
            if not line.endswith("\n"):
                break  # still being written
            chk.feed_line(line)


def run_live(chk, args):
    token = "sparkplug_check/ready/%d" % os.getpid()
    base = ["-h", args.host, "-p", str(args.port)] + args.mqtt_arg
    cmd = ["mosquitto_sub"] + base + ["-V", "mqttv5", "--retain-as-published", "-q", "2",
                                      "-t", NAMESPACE + "/#", "-t", token, "-F", SUB_FORMAT]
    sub = subprocess.Popen(cmd, stdout=subprocess.PIPE, text=True, errors="replace")
    lines = queue.Queue()

    def reader():
        for line in sub.stdout:
            lines.put(line)
        lines.put(None)

    threading.Thread(target=reader, daemon=True).start()
    record = open(args.record, "a", encoding="utf-8") if args.record else None
    stop = threading.Event()
    for sig in (signal.SIGTERM, signal.SIGINT):
        signal.signal(sig, lambda *_: stop.set())
    ready = False
    deadline = time.monotonic() + args.duration if args.duration > 0 else None
    next_probe = 0.0
    try:
        while not stop.is_set():
            now = time.monotonic()
            if deadline is not None and now >= deadline:
                break
            if not ready and now >= next_probe:
                # Subscribed once our own probe comes back through the broker.
                subprocess.run(["mosquitto_pub"] + base + ["-t", token, "-m", "ready"], stderr=subprocess.DEVNULL)
                next_probe = now + 0.5
            try:
                line = lines.get(timeout=0.1)
            except queue.Empty:
                continue
            if line is None:
                print("sparkplug_check: mosquitto_sub ended (exit %s)" % sub.wait(), file=sys.stderr)
                return 3
            if record:
                record.write(line)
                record.flush()
            if not ready and line.rstrip("\n").endswith(" " + token):
                ready = True
                chk.emit({"event": "ready", "topic": NAMESPACE + "/#"})
                if args.ready_file:
                    open(args.ready_file, "w").close()
            chk.feed_line(line)  # every line, so line numbers match the --record file
            if args.until_met and not chk.unmet():
                break
    finally:
        sub.terminate()
        sub.wait()
        if record:
            record.close()
    return None


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--capture", metavar="FILE", help="check a recorded file ('-': stdin) instead of a broker")
    ap.add_argument("--host", default="127.0.0.1")
    ap.add_argument("--port", type=int, default=1883)
    ap.add_argument("--mqtt-arg", action="append", default=[], metavar="ARG",
                    help="extra mosquitto_sub/mosquitto_pub argument (credentials, TLS), repeatable")
    ap.add_argument("--record", metavar="FILE", help="append every received line to FILE")
    ap.add_argument("--ready-file", metavar="FILE", help="created once the subscription is in place")
    ap.add_argument("--duration", type=float, default=0, help="seconds to listen (0: until SIGTERM/SIGINT)")
    ap.add_argument("--until-met", action="store_true", help="stop as soon as every expectation is met")
    ap.add_argument("--proto", default=DEFAULT_PROTO, help="sparkplug_b.proto (default: the project's)")
    ap.add_argument("--group", help="check only this group id")
    ap.add_argument("--edge", help="check only this edge node id")
    ap.add_argument("--decode", action="store_true", help="print every decoded message as a JSON line")
    ap.add_argument("--allow-late-start", action="store_true",
                    help="an edge node's messages before its first NBIRTH are skipped (joined a running session)")
    ap.add_argument("--allow-bdseq-skips", action="store_true",
                    help="a new session's bdSeq may go up by more than one (failed CONNECT attempts)")
    ap.add_argument("--no-clock", action="store_true", help="do not compare timestamps with the arrival time")
    ap.add_argument("--max-skew", type=float, default=600, help="seconds a timestamp may differ (default 600)")
    g = ap.add_argument_group("expectations (counted from --from-line on)")
    g.add_argument("--from-line", type=int, default=0, help="count expectations only after this capture line")
    g.add_argument("--min-nbirths", type=int, default=0)
    g.add_argument("--min-dbirths", type=int, default=0)
    g.add_argument("--min-ddata", type=int, default=0)
    g.add_argument("--min-ddeaths", type=int, default=0)
    g.add_argument("--min-ndeaths", type=int, default=0)
    g.add_argument("--expect-ndeath", action="store_true", help="same as --min-ndeaths 1")
    g.add_argument("--expect-dbirth", action="append", default=[], metavar="DEVICE")
    g.add_argument("--expect-birth-metric", action="append", default=[], metavar="DEVICE/METRIC",
                   help="a DBIRTH of DEVICE has the metric (DEVICE empty: an NBIRTH)")
    g.add_argument("--expect-data", action="append", default=[], metavar="DEVICE/METRIC[=VALUE]",
                   help="a DDATA of DEVICE carries the metric, with that value if given (DEVICE empty: NDATA)")
    g.add_argument("--expect-birth-object", action="append", default=[], metavar="DEVICE/INDEXh:SUB[=VALUE]",
                   help="the latest DBIRTH of DEVICE has a metric for that object (properties index, subIndex), "
                        "with that value if given")
    g.add_argument("--expect-data-object", action="append", default=[], metavar="DEVICE/INDEXh:SUB[=VALUE]",
                   help="a DDATA of DEVICE carries the metric born for that object, with that value if given")
    ap.add_argument("--lookup", metavar="DEVICE/INDEXh:SUB",
                    help="(with --capture) print NAME=DATATYPE of the metric born for that object and exit "
                         "(status 2: none)")
    args = ap.parse_args(argv)
    if args.expect_ndeath:
        args.min_ndeaths = max(args.min_ndeaths, 1)

    with tempfile.TemporaryDirectory(prefix="sparkplug-check-") as tmp:
        try:
            pb = generate_module(args.proto, tmp)
        except (RuntimeError, subprocess.CalledProcessError, ImportError) as e:
            print("sparkplug_check: cannot generate the decoder from %s: %s" % (args.proto, e), file=sys.stderr)
            return 3
        chk = Checker(pb, args)
        if args.lookup:
            chk.out = sys.stderr  # stdout is the answer alone
        try:
            if args.capture:
                run_capture(chk, args.capture)
                if args.lookup:
                    found = chk.lookup(args.lookup)
                    if found is None:
                        return 2
                    print(found)
                    return 0
            else:
                rc = run_live(chk, args)
                if rc is not None:
                    return rc
        except (OSError, ValueError) as e:
            print("sparkplug_check: %s" % e, file=sys.stderr)
            return 3
        s = chk.summary()
    verdict = "ok" if s["ok"] else ("rules broken: %s" % ", ".join(s["rules_broken"]) if s["violations"]
                                    else "unmet: %s" % "; ".join(s["unmet"]))
    print("sparkplug_check: %d messages, %s" % (s["messages"], verdict), file=sys.stderr)
    if s["violations"]:
        return 1
    return 0 if not s["unmet"] else 2


if __name__ == "__main__":
    sys.exit(main())
