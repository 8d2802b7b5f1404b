#!/usr/bin/python3
"""Self-test of tests/tools/sparkplug_check.py without a gateway or a broker.

Builds Sparkplug B sessions with code generated from proto/sparkplug_b.proto,
writes them as a capture (the lines `mosquitto_sub -F '%U %r %q %x %t'`
prints) and runs the checker on it: a session that keeps every rule of the
facts sheet's section A must pass; each broken rule must be flagged with its
rule id (and nothing else), so a checker that accepts everything, or blames
the wrong rule, fails here.
"""

import json
import os
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
CHECKER = os.path.join(HERE, "sparkplug_check.py")
sys.dont_write_bytecode = True  # no __pycache__ in the source tree
sys.path.insert(0, HERE)
import sparkplug_check  # noqa: E402

G, E = "plant", "gw1"
NOW_MS = 1_790_000_000_000
INT64, UINT8, UINT16, INT16, UINT32, BOOLEAN, STRING = 4, 5, 6, 2, 7, 11, 12


class Builder:
    """One edge node's messages, seq counted like an edge node does."""

    def __init__(self, pb, aliases=False):
        self.pb = pb
        self.lines = []
        self.seq = 0
        self.t = NOW_MS
        self.aliases = aliases
        self.next_alias = 1

    # -- metrics
    def metric(self, p, name, datatype, value, birth=True, index=None, alias=None, props=None):
        m = p.metrics.add()
        if birth or alias is None:
            m.name = name
        if alias is not None:
            m.alias = alias
        if birth:
            m.datatype = datatype
        m.timestamp = self.t
        field = sparkplug_check.VALUE_FIELD[datatype]
        if value is None:
            m.is_null = True
        else:
            setattr(m, field, value)
        if index is not None:
            for key, t, v in props or (("index", UINT16, index[0]), ("subIndex", UINT8, index[1])):
                m.properties.keys.append(key)
                pv = m.properties.values.add()
                pv.type = t
                pv.int_value = v
        return m

    def payload(self, seq=True):
        p = self.pb.Payload()
        self.t += 10
        p.timestamp = self.t
        if seq:
            p.seq = self.seq
            self.seq = (self.seq + 1) % 256
        return p

    def add(self, mtype, p, device=None, qos=None, retain=False, raw=None):
        topic = "spBv1.0/%s/%s/%s" % (G, mtype, E) + ("/" + device if device else "")
        if qos is None:
            qos = 1 if mtype == "NDEATH" else 0
        data = raw if raw is not None else p.SerializeToString()
        self.lines.append("%.9f %d %d %s %s\n" % (self.t / 1000.0, int(retain), qos, data.hex(), topic))
        return p

    # -- messages
    def nbirth(self, bd_seq, **kw):
        self.seq = 0
        p = self.payload()
        self.metric(p, "bdSeq", INT64, bd_seq)
        self.metric(p, "Node Control/Rebirth", BOOLEAN, False)
        self.metric(p, "Network 1/Bus State", STRING, "error-active", alias=self.alias())
        return self.add("NBIRTH", p, **kw)

    def alias(self):
        if not self.aliases:
            return None
        self.next_alias += 1
        return self.next_alias - 1

    def dbirth(self, device, **kw):
        p = self.payload()
        self.metric(p, "Speed", INT16, (-5) & 0xFFFFFFFF, index=(0x6000, 1), alias=self.alias())
        self.metric(p, "Setpoint", UINT32, 7, index=(0x6200, 0), alias=self.alias())
        self.metric(p, "Serial", STRING, None, index=(0x1018, 4), alias=self.alias())
        self.metric(p, "Node/State", STRING, "operational", alias=self.alias())
        self.metric(p, "EMCY/Error Code", UINT16, 0, alias=self.alias())
        self.metric(p, "Device Control/Rebirth", BOOLEAN, False)
        return self.add("DBIRTH", p, device, **kw)

    def ddata(self, device, value, alias=None, **kw):
        p = self.payload()
        self.metric(p, "Speed", INT16, value & 0xFFFFFFFF, birth=False, alias=alias)
        return self.add("DDATA", p, device, **kw)

    def ndata(self, **kw):
        p = self.payload()
        self.metric(p, "Network 1/Bus State", STRING, "error-passive", birth=False)
        return self.add("NDATA", p, **kw)

    def ddeath(self, device):
        return self.add("DDEATH", self.payload(), device)

    def ndeath(self, bd_seq, **kw):
        p = self.pb.Payload()
        p.timestamp = 0  # the Will's timestamp is not meaningful (facts A.3)
        self.metric(p, "bdSeq", INT64, bd_seq)
        return self.add("NDEATH", p, **kw)

    def ncmd_rebirth(self):
        p = self.payload(seq=False)
        m = p.metrics.add()
        m.name = "Node Control/Rebirth"
        m.datatype = BOOLEAN
        m.boolean_value = True
        return self.add("NCMD", p)

    # -- the good story
    def good_session(self):
        self.nbirth(0)
        self.dbirth("net1-node5")
        self.dbirth("pump")
        self.ddata("net1-node5", -7)
        self.ndata()
        # seq wraps at 255 (facts A.5)
        for i in range(300):
            self.ddata("pump", i)
        self.ncmd_rebirth()
        self.nbirth(0)  # rebirth: seq 0, same bdSeq (facts A.6)
        self.dbirth("net1-node5")
        self.dbirth("pump")
        self.ddata("pump", 1)
        self.ddeath("pump")
        self.dbirth("pump")  # back again
        self.ddata("pump", 42)
        self.ndeath(0)  # clean stop: explicit NDEATH ...
        self.ndeath(0)  # ... and on MQTT 5 the Will as well: a duplicate, not an error
        self.nbirth(1)  # restart: bdSeq + 1 (facts A.5)
        self.dbirth("net1-node5")
        self.ndeath(1)  # kill -9: the Will
        return self


class CheckerTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory(prefix="sparkplug-check-test-")
        cls.pb = sparkplug_check.generate_module(sparkplug_check.DEFAULT_PROTO, cls.tmp.name)

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def run_checker(self, lines, *args):
        path = os.path.join(self.tmp.name, "capture.txt")
        with open(path, "w") as f:
            f.writelines(lines)
        r = subprocess.run([sys.executable, CHECKER, "--capture", path] + list(args), capture_output=True, text=True)
        events = [json.loads(x) for x in r.stdout.splitlines()]
        summary = [e for e in events if e["event"] == "summary"]
        self.assertEqual(len(summary), 1, r.stdout + r.stderr)
        return r.returncode, [e for e in events if e["event"] == "violation"], summary[0]

    def good(self, aliases=False):
        return Builder(self.pb, aliases).good_session()

    def assert_flagged(self, lines, rule, *args):
        rc, violations, _ = self.run_checker(lines, *args)
        self.assertEqual(rc, 1, violations)
        self.assertEqual({v["rule"] for v in violations}, {rule}, json.dumps(violations, indent=1))
        for v in violations:
            self.assertTrue(v["fact"] and v["message"] and v["line"] > 0, v)

    # ---- the good ones ---------------------------------------------------
    def test_a_session_keeping_every_rule_passes(self):
        b = self.good()
        rc, violations, s = self.run_checker(b.lines, "--min-nbirths", "3", "--min-dbirths", "6", "--expect-ndeath",
                                             "--expect-dbirth", "pump", "--expect-data", "pump/Speed=42",
                                             "--expect-data", "net1-node5/Speed=-7",
                                             "--expect-birth-metric", "net1-node5/Serial",
                                             "--expect-birth-metric", "/Network 1/Bus State",
                                             "--expect-data", "/Network 1/Bus State=error-passive")
        self.assertEqual((rc, violations, s["unmet"]), (0, [], []))
        self.assertEqual(s["sessions"], {G + "/" + E: [0, 1]})
        self.assertEqual(s["counts"]["NDEATH"], 3)

    def test_aliases_born_with_names_and_data_by_alias_pass(self):
        b = Builder(self.pb, aliases=True)
        b.nbirth(3)
        b.dbirth("pump")  # aliases 2..6
        b.ddata("pump", 9, alias=2)
        rc, violations, s = self.run_checker(b.lines, "--expect-data", "pump/Speed=9")
        self.assertEqual((rc, violations, s["unmet"]), (0, [], []))
        b.ddata("pump", -9, alias=2)
        path = os.path.join(self.tmp.name, "capture.txt")
        self.run_checker(b.lines)
        r = subprocess.run([sys.executable, CHECKER, "--capture", path, "--decode"], capture_output=True, text=True)
        last = [e for e in map(json.loads, r.stdout.splitlines()) if e["event"] == "message"][-1]
        # As on the wire (alias, no name or datatype), typed and named by the birth.
        self.assertEqual(last["metrics"], [{"alias": 2, "value": -9, "born_name": "Speed"}])

    def test_bdseq_wraps_from_255_to_0(self):
        b = Builder(self.pb)
        b.nbirth(255)
        b.ndeath(255)
        b.nbirth(0)
        self.assertEqual(self.run_checker(b.lines)[0], 0)

    def test_decode_shows_values_typed_and_the_canopen_address(self):
        b = Builder(self.pb)
        b.nbirth(0)
        b.dbirth("pump")
        b.ddata("pump", -300)
        rc, _, _ = self.run_checker(b.lines)
        path = os.path.join(self.tmp.name, "capture.txt")
        r = subprocess.run([sys.executable, CHECKER, "--capture", path, "--decode"], capture_output=True, text=True)
        msgs = [e for e in map(json.loads, r.stdout.splitlines()) if e["event"] == "message"]
        self.assertEqual([m["type"] for m in msgs], ["NBIRTH", "DBIRTH", "DDATA"])
        speed = msgs[1]["metrics"][0]
        self.assertEqual((speed["name"], speed["index"], speed["subIndex"], speed["value"]), ("Speed", 0x6000, 1, -5))
        self.assertEqual(msgs[2]["metrics"][0]["value"], -300)  # Int16 two's complement (facts A.7)
        self.assertEqual(msgs[2]["seq"], 2)

    def test_objects_by_their_canopen_address(self):
        b = Builder(self.pb)
        b.nbirth(0)
        b.dbirth("pump")
        b.ddata("pump", 12)
        rc, violations, s = self.run_checker(b.lines, "--expect-birth-object", "pump/6200h:0=7",
                                             "--expect-birth-object", "pump/1018h:4=null",
                                             "--expect-data-object", "pump/0x6000:1=12")
        self.assertEqual((rc, s["unmet"]), (0, []))
        rc, _, s = self.run_checker(b.lines, "--expect-birth-object", "pump/6200h:1",
                                    "--expect-birth-object", "pump/6200h:0=8",
                                    "--expect-data-object", "pump/6000h:1=13")
        self.assertEqual((rc, len(s["unmet"])), (2, 3))
        path = os.path.join(self.tmp.name, "capture.txt")
        r = subprocess.run([sys.executable, CHECKER, "--capture", path, "--lookup", "pump/6000h:1"],
                           capture_output=True, text=True)
        self.assertEqual((r.returncode, r.stdout), (0, "Speed=Int16\n"))
        r = subprocess.run([sys.executable, CHECKER, "--capture", path, "--lookup", "pump/6001h:1"],
                           capture_output=True, text=True)
        self.assertEqual((r.returncode, r.stdout), (2, ""))

    def test_an_unmet_expectation_exits_2_and_says_which(self):
        rc, violations, s = self.run_checker(self.good().lines, "--min-dbirths", "99",
                                             "--expect-data", "pump/Speed=999")
        self.assertEqual((rc, violations), (2, []))
        self.assertEqual(len(s["unmet"]), 2, s["unmet"])

    def test_from_line_counts_expectations_only_after_it(self):
        b = Builder(self.pb)
        b.nbirth(0)
        b.dbirth("pump")
        n = len(b.lines)
        self.assertEqual(self.run_checker(b.lines, "--from-line", str(n), "--min-dbirths", "1")[0], 2)
        b.ncmd_rebirth()
        b.nbirth(0)
        b.dbirth("pump")
        self.assertEqual(self.run_checker(b.lines, "--from-line", str(n), "--min-dbirths", "1",
                                          "--min-nbirths", "1")[0], 0)

    def test_an_unfinished_last_line_is_left_for_later(self):
        b = Builder(self.pb)
        b.nbirth(0)
        b.ddata("pump", 1)  # would be DDATA before DBIRTH
        lines = b.lines[:-1] + [b.lines[-1][:-1]]
        self.assertEqual(self.run_checker(lines)[0], 0)

    def test_late_start_skips_a_running_session_until_its_nbirth(self):
        b = Builder(self.pb)
        b.seq = 17
        b.ddata("pump", 1)
        b.ncmd_rebirth()
        b.nbirth(4)
        b.dbirth("pump")
        self.assert_flagged(b.lines, "birth-order")
        self.assertEqual(self.run_checker(b.lines, "--allow-late-start")[0], 0)

    # ---- each broken rule, flagged as that rule ----------------------------
    def test_seq_gap_facts_a5(self):
        b = Builder(self.pb)
        b.nbirth(0)
        b.dbirth("pump")
        b.seq += 1
        b.ddata("pump", 1)
        self.assert_flagged(b.lines, "seq")

    def test_seq_not_wrapping_at_255_facts_a5(self):
        b = Builder(self.pb)
        b.nbirth(0)
        b.dbirth("pump")
        lines = b.lines
        for _ in range(254):
            b.ddata("pump", 1)
        p = b.pb.Payload()
        p.timestamp = b.t
        p.seq = 256
        b.metric(p, "Speed", INT16, 1, birth=False)
        b.add("DDATA", p, "pump")
        self.assert_flagged(lines, "seq")

    def test_ndeath_with_seq_facts_a5(self):
        b = Builder(self.pb)
        b.nbirth(0)
        p = b.pb.Payload()
        b.metric(p, "bdSeq", INT64, 0)
        p.seq = 1
        b.add("NDEATH", p)
        self.assert_flagged(b.lines, "seq")

    def test_nbirth_seq_not_0_facts_a5(self):
        b = Builder(self.pb)
        b.nbirth(0)
        b.lines.pop()
        b.seq = 5
        p = b.payload()
        b.metric(p, "bdSeq", INT64, 0)
        b.metric(p, "Node Control/Rebirth", BOOLEAN, False)
        b.add("NBIRTH", p)
        self.assert_flagged(b.lines, "nbirth-seq")

    def test_ddata_before_dbirth_facts_a3(self):
        b = Builder(self.pb)
        b.nbirth(0)
        b.ddata("pump", 1)
        self.assert_flagged(b.lines, "birth-order")

    def test_dbirth_before_nbirth_facts_a3(self):
        b = Builder(self.pb)
        b.dbirth("pump")
        self.assert_flagged(b.lines, "birth-order")

    def test_ddata_after_ddeath_facts_a3(self):
        b = Builder(self.pb)
        b.nbirth(0)
        b.dbirth("pump")
        b.ddeath("pump")
        b.ddata("pump", 1)
        self.assert_flagged(b.lines, "birth-order")

    def test_data_after_ndeath_before_the_next_nbirth_facts_a4_4(self):
        b = Builder(self.pb)
        b.nbirth(0)
        b.ndeath(0)
        b.ndata()
        self.assert_flagged(b.lines, "birth-order")

    def test_data_after_rebirth_before_every_dbirth_facts_a6(self):
        b = Builder(self.pb)
        b.nbirth(0)
        b.dbirth("pump")
        b.dbirth("net1-node5")
        b.ncmd_rebirth()
        b.nbirth(0)
        b.dbirth("pump")
        b.ddata("pump", 3)
        self.assert_flagged(b.lines, "rebirth")

    def test_ndeath_with_wrong_bdseq_facts_a5(self):
        b = Builder(self.pb)
        b.nbirth(4)
        b.ndeath(3)
        self.assert_flagged(b.lines, "ndeath-bdseq")

    def test_next_session_bdseq_not_plus_one_facts_a5(self):
        b = Builder(self.pb)
        b.nbirth(4)
        b.ndeath(4)
        b.nbirth(6)
        self.assert_flagged(b.lines, "bdseq-sequence")
        self.assertEqual(self.run_checker(b.lines, "--allow-bdseq-skips")[0], 0)

    def test_rebirth_with_another_bdseq_facts_a5(self):
        b = Builder(self.pb)
        b.nbirth(4)
        b.ncmd_rebirth()
        b.nbirth(5)
        self.assert_flagged(b.lines, "bdseq-sequence")

    def test_retained_nbirth_facts_a3(self):
        b = Builder(self.pb)
        b.nbirth(0, retain=True)
        self.assert_flagged(b.lines, "qos-retain")

    def test_ndeath_at_qos_0_facts_a3(self):
        b = Builder(self.pb)
        b.nbirth(0)
        b.ndeath(0, qos=0)
        self.assert_flagged(b.lines, "qos-retain")

    def test_ddata_at_qos_1_facts_a3(self):
        b = Builder(self.pb)
        b.nbirth(0)
        b.dbirth("pump")
        b.ddata("pump", 1, qos=1)
        self.assert_flagged(b.lines, "qos-retain")

    def test_missing_index_property_contract(self):
        b = Builder(self.pb)
        b.nbirth(0)
        p = b.payload()
        b.metric(p, "Speed", INT16, 1, index=(0x6000, 1), props=(("subIndex", UINT8, 1),))
        b.add("DBIRTH", p, "pump")
        self.assert_flagged(b.lines, "properties")

    def test_subindex_property_of_the_wrong_type_contract(self):
        b = Builder(self.pb)
        b.nbirth(0)
        p = b.payload()
        b.metric(p, "Speed", INT16, 1, index=(0x6000, 1), props=(("index", UINT16, 0x6000), ("subIndex", UINT16, 1)))
        b.add("DBIRTH", p, "pump")
        self.assert_flagged(b.lines, "properties")

    def test_nbirth_without_bdseq_facts_a3(self):
        b = Builder(self.pb)
        p = b.payload()
        b.metric(p, "Node Control/Rebirth", BOOLEAN, False)
        b.add("NBIRTH", p)
        self.assert_flagged(b.lines, "bdseq-metric")

    def test_bdseq_not_int64_facts_a5(self):
        b = Builder(self.pb)
        p = b.payload()
        b.metric(p, "bdSeq", UINT32, 0)
        b.metric(p, "Node Control/Rebirth", BOOLEAN, False)
        b.add("NBIRTH", p)
        self.assert_flagged(b.lines, "bdseq-metric")

    def test_nbirth_without_node_control_rebirth_facts_a6(self):
        b = Builder(self.pb)
        p = b.payload()
        b.metric(p, "bdSeq", INT64, 0)
        b.add("NBIRTH", p)
        self.assert_flagged(b.lines, "rebirth-metric")

    def test_node_control_rebirth_true_in_nbirth_facts_a6(self):
        b = Builder(self.pb)
        p = b.payload()
        b.metric(p, "bdSeq", INT64, 0)
        b.metric(p, "Node Control/Rebirth", BOOLEAN, True)
        b.add("NBIRTH", p)
        self.assert_flagged(b.lines, "rebirth-metric")

    def test_node_control_rebirth_with_an_alias_facts_a6(self):
        b = Builder(self.pb)
        p = b.payload()
        b.metric(p, "bdSeq", INT64, 0)
        b.metric(p, "Node Control/Rebirth", BOOLEAN, False, alias=99)
        b.add("NBIRTH", p)
        self.assert_flagged(b.lines, "alias")

    def test_alias_used_twice_over_the_edge_node_facts_a7(self):
        b = Builder(self.pb, aliases=True)
        b.nbirth(0)
        b.dbirth("pump")
        b.next_alias = 2
        b.dbirth("net1-node5")
        self.assert_flagged(b.lines, "alias")

    def test_data_by_name_of_an_aliased_metric_facts_a7(self):
        b = Builder(self.pb, aliases=True)
        b.nbirth(0)
        b.dbirth("pump")
        b.ddata("pump", 1)
        self.assert_flagged(b.lines, "alias")

    def test_ddata_of_a_metric_never_born_facts_a6(self):
        b = Builder(self.pb)
        b.nbirth(0)
        b.dbirth("pump")
        p = b.payload()
        b.metric(p, "Torque", INT16, 1, birth=False)
        b.add("DDATA", p, "pump")
        self.assert_flagged(b.lines, "unknown-metric")

    def test_ddata_of_an_alias_never_born_facts_a6(self):
        b = Builder(self.pb, aliases=True)
        b.nbirth(0)
        b.dbirth("pump")
        b.ddata("pump", 1, alias=77)
        self.assert_flagged(b.lines, "unknown-metric")

    def test_value_in_the_wrong_field_for_its_datatype_facts_a7(self):
        b = Builder(self.pb)
        b.nbirth(0)
        b.dbirth("pump")
        p = b.payload()
        m = b.metric(p, "Speed", INT16, 1, birth=False)
        m.long_value = 1  # Int16 travels in int_value
        b.add("DDATA", p, "pump")
        self.assert_flagged(b.lines, "value-type")

    def test_int16_in_its_own_width_contract(self):
        # Contract: negative Int8/Int16 go sign-extended to 32 bits (Tahu
        # Java, Ignition); -5 as 0xFFFB reads as 65531 in Tahu JS.
        b = Builder(self.pb)
        b.nbirth(0)
        b.dbirth("pump")
        p = b.payload()
        b.metric(p, "Speed", INT16, (-5) & 0xFFFF, birth=False)
        b.add("DDATA", p, "pump")
        self.assert_flagged(b.lines, "value-type")

    def test_uint32_in_int_value_contract(self):
        # Contract: UInt32 travels in long_value (tahu issues 131 and 397).
        b = Builder(self.pb)
        b.nbirth(0)
        b.dbirth("pump")
        p = b.payload()
        m = b.metric(p, "Setpoint", UINT32, 7, birth=False)
        m.int_value = 7
        b.add("DDATA", p, "pump")
        self.assert_flagged(b.lines, "value-type")

    def test_birth_metric_without_datatype_facts_a3(self):
        b = Builder(self.pb)
        b.nbirth(0)
        p = b.payload()
        b.metric(p, "Speed", INT16, 1, index=(0x6000, 1)).ClearField("datatype")
        b.add("DBIRTH", p, "pump")
        self.assert_flagged(b.lines, "metric")

    def test_birth_metric_without_value_facts_a3(self):
        b = Builder(self.pb)
        b.nbirth(0)
        p = b.payload()
        b.metric(p, "Speed", INT16, 1, index=(0x6000, 1)).ClearField("int_value")
        b.add("DBIRTH", p, "pump")
        self.assert_flagged(b.lines, "metric")

    def test_ndeath_with_more_than_bdseq_facts_a3(self):
        b = Builder(self.pb)
        b.nbirth(0)
        p = b.ndeath(0)
        b.lines.pop()
        b.metric(p, "Node/State", STRING, "x")
        b.add("NDEATH", p)
        self.assert_flagged(b.lines, "ndeath")

    def test_payload_without_timestamp_facts_a3(self):
        b = Builder(self.pb)
        b.nbirth(0)
        b.dbirth("pump")
        p = b.payload()
        b.metric(p, "Speed", INT16, 1, birth=False)
        p.ClearField("timestamp")
        b.add("DDATA", p, "pump")
        self.assert_flagged(b.lines, "timestamp")

    def test_timestamp_in_seconds_not_utc_ms_facts_a4_8(self):
        b = Builder(self.pb)
        b.nbirth(0)
        b.dbirth("pump")
        p = b.payload()
        b.metric(p, "Speed", INT16, 1, birth=False)
        p.timestamp = b.t // 1000
        b.add("DDATA", p, "pump")
        self.assert_flagged(b.lines, "clock")

    def test_bytes_that_are_not_a_payload_facts_a7(self):
        b = Builder(self.pb)
        b.nbirth(0)
        b.add("DDATA", None, "pump", raw=b"\xff\xff\xff")
        self.assert_flagged(b.lines, "decode")

    def test_device_topic_without_device_id_facts_a2(self):
        b = Builder(self.pb)
        b.nbirth(0)
        b.add("DDATA", b.payload())
        self.assert_flagged(b.lines, "topic")

    def test_command_with_seq_facts_a5(self):
        b = Builder(self.pb)
        b.nbirth(0)
        p = b.pb.Payload()
        p.timestamp = b.t
        p.seq = 3
        b.add("NCMD", p)
        self.assert_flagged(b.lines, "command")


if __name__ == "__main__":
    unittest.main(verbosity=2)
