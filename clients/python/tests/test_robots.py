"""Tests of manipid_client's URDF robot API against a real `manipid serve` (local_server()).

The data come from the real binary (robot_data.py): a 7-joint arm's excitation through
`manipid torque` with a known truth, once at a uniform 1 kHz, once as a jittery logger records
it (time stamps ± 0.25 ms, missing samples, stale repeated rows), a noise-free run and a
second excitation for validation.

    MANIPID_BIN=build/debug/server/manipid python3 -m unittest discover -s clients/python/tests -v
"""
from __future__ import annotations

import contextlib
import math
import os
import re
import shutil
import sqlite3
import struct
import subprocess
import sys
import tempfile
import unittest
import xml.etree.ElementTree as ElementTree
from pathlib import Path

PACKAGE_ROOT = Path(__file__).resolve().parent.parent  # clients/python
REPOSITORY = PACKAGE_ROOT.parent.parent
sys.path.insert(0, str(PACKAGE_ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from manipid_client import (Client, Dataset, Estimate, Job, JobCancelled, ManipidError, Robot,  # noqa: E402
                            RobotResult, base_value, local_server)
from robot_data import robot_runs  # noqa: E402

if not os.environ.get("MANIPID_BIN"):
    for candidate in ("build/debug/server/manipid", "build/release/server/manipid"):
        if os.access(REPOSITORY / candidate, os.X_OK):
            os.environ["MANIPID_BIN"] = str(REPOSITORY / candidate)
            break
BINARY = os.path.abspath(os.environ["MANIPID_BIN"]) if os.environ.get("MANIPID_BIN") else ""

PANDA = REPOSITORY / "examples" / "robots" / "panda_like.urdf"
UR5 = REPOSITORY / "examples" / "robots" / "ur5_like.urdf"
PANDA_JOINTS = [f"panda_joint{k}" for k in range(1, 8)]


def within(test: unittest.TestCase, estimate: Estimate, truth: float, sigmas: float = 4.0, what: str = "") -> None:
    """The truth lies within `sigmas` standard errors of the estimate (and the error is a real one)."""
    test.assertIsNotNone(estimate.std_error, what)
    test.assertGreater(estimate.std_error, 0.0, what)
    test.assertLessEqual(abs(estimate.estimate - truth), sigmas * estimate.std_error,
                         f"{what}: {estimate.estimate} ± {estimate.std_error}, truth {truth}")


@unittest.skipUnless(BINARY, "no manipid binary: set MANIPID_BIN or build build/release")
class RobotsAgainstServer(unittest.TestCase):
    """One server, one set of runs and one identification of the jittery run for the class."""

    @classmethod
    def setUpClass(cls) -> None:
        cls.stack = contextlib.ExitStack()
        cls.directory = cls.stack.enter_context(tempfile.TemporaryDirectory(prefix="manipid-robot-test-"))
        cls.runs = robot_runs(BINARY, str(PANDA), cls.directory)
        cls.truth = cls.runs["truth"]
        cls.url = cls.stack.enter_context(local_server(workers=2))
        cls.client = Client(cls.url)
        cls.arm = cls.client.upload_robot(PANDA)
        cls.jitter = cls.client.upload_dataset(cls.runs["jitter"], name="jittery run")
        cls.check = cls.client.upload_dataset(cls.runs["check"])
        cls.job = cls.client.identify(cls.jitter, robot=cls.arm, friction=["viscous", "coulomb", "offset"],
                                      validate=cls.check)
        cls.result = cls.job.robot_result(timeout=300)

    @classmethod
    def tearDownClass(cls) -> None:
        cls.stack.close()

    # --- robots ----------------------------------------------------------------------------
    def test_upload_xml_and_get_it_back_byte_for_byte(self) -> None:
        arm = self.arm
        self.assertIsInstance(arm, Robot)
        self.assertRegex(arm.id, r"^rb_[0-9a-f]+$")
        self.assertEqual(str(arm), arm.id)
        self.assertEqual((arm.name, arm["robot_name"], arm.base_link, arm.tip_link),
                         ("panda_like", "panda_like", "panda_link0", "panda_link8"))
        self.assertEqual(arm.joint_names, PANDA_JOINTS)
        self.assertEqual(arm.parameters["names"][:4], ["m1", "mx1", "my1", "mz1"])
        self.assertEqual(arm.parameters["urdf_values"]["m3"], 2.5)
        self.assertTrue(any("panda_link8" in warning for warning in arm.warnings))
        self.assertEqual(self.client.robot_urdf_bytes(arm), PANDA.read_bytes())
        self.assertEqual(self.client.robot_urdf(arm.id), PANDA.read_text(encoding="utf-8"))
        self.assertEqual(arm.urdf(), PANDA.read_text(encoding="utf-8"))
        again = self.client.robot({"id": arm.id})  # ids, Robots and their dicts are all accepted
        self.assertEqual(again.data, arm.data)

    def test_upload_text_and_json_forms_with_name_and_tip(self) -> None:
        text = PANDA.read_text(encoding="utf-8")
        named = self.client.upload_robot(text, name="arm from text")
        self.assertEqual((named.name, len(named.joints)), ("arm from text", 7))
        short = self.client.upload_robot(PANDA, name="six", tip="panda_link6")  # XML form: query parameters
        self.assertEqual((short.name, short.tip_link, short.joint_names), ("six", "panda_link6", PANDA_JOINTS[:6]))
        json_form = self.client.upload_robot(PANDA, name="json six", tip="panda_link6", form="json")
        self.assertEqual((json_form.name, json_form.tip_link, len(json_form.joints)), ("json six", "panda_link6", 6))
        self.assertEqual(self.client.robot_urdf_bytes(json_form), PANDA.read_bytes())
        ur5 = self.client.upload_robot(UR5.read_bytes())
        self.assertEqual(len(ur5.joints), 6)
        self.assertEqual(ur5.urdf(), UR5.read_text(encoding="utf-8"))
        listed = [robot.id for robot in self.client.robots(page_size=1)]  # one per page
        for robot in (named, short, json_form, ur5, self.arm):
            self.assertEqual(listed.count(robot.id), 1)

    def test_idempotent_replay(self) -> None:
        first = self.client.upload_robot(PANDA, name="replayed", idempotency_key="test-robot-replay")
        second = self.client.upload_robot(PANDA, name="replayed", idempotency_key="test-robot-replay")
        self.assertEqual(second.id, first.id)
        self.assertEqual([robot.id for robot in self.client.robots()].count(first.id), 1)
        with self.assertRaises(ManipidError) as caught:  # the same key, another document
            self.client.upload_robot(UR5, name="replayed", idempotency_key="test-robot-replay")
        self.assertEqual((caught.exception.status, caught.exception.code), (422, "IDEMPOTENCY_MISMATCH"))

    def test_a_document_the_server_cannot_use(self) -> None:
        with self.assertRaises(ManipidError) as caught:
            self.client.upload_robot('<robot name="broken"><link name="a"/>')
        self.assertEqual((caught.exception.status, caught.exception.code, caught.exception.field),
                         (422, "INVALID_FIELD", "urdf"))
        with self.assertRaises(ManipidError) as caught:
            self.client.upload_robot(PANDA, tip="no_such_link")
        self.assertEqual((caught.exception.status, caught.exception.field), (422, "tip"))
        with self.assertRaises(FileNotFoundError):
            self.client.upload_robot(os.path.join(self.directory, "missing.urdf"))

    def test_delete(self) -> None:
        robot = self.client.upload_robot(UR5, name="to delete")
        self.assertIsNone(self.client.delete_robot(robot))
        for action in (lambda: self.client.robot(robot.id), lambda: self.client.delete_robot(robot.id),
                       lambda: self.client.robot_urdf(robot.id)):
            with self.assertRaises(ManipidError) as caught:
                action()
            self.assertEqual((caught.exception.status, caught.exception.code), (404, "NOT_FOUND"))

    def test_deleting_a_robot_in_use_is_refused(self) -> None:
        robot = self.client.upload_robot(PANDA, name="busy")
        job = self.client.design_excitation(robot)  # the full default budget: seconds, not milliseconds
        self.assertIn(job.state, ("queued", "running"))
        with self.assertRaises(ManipidError) as caught:
            self.client.delete_robot(robot)
        self.assertEqual((caught.exception.status, caught.exception.code, caught.exception.field), (409, "CONFLICT", "id"))
        job.cancel()
        with self.assertRaises(JobCancelled):
            job.wait(timeout=120)
        self.client.delete_robot(robot)  # nothing uses it any more
        with self.assertRaises(ManipidError):
            self.client.robot(robot)

    # --- identification --------------------------------------------------------------------
    def test_jittery_dataset_is_stored_as_measured_and_resampled(self) -> None:
        self.assertIsInstance(self.jitter, Dataset)
        self.assertFalse(self.jitter.uniform)
        self.assertEqual((self.jitter.samples, self.jitter.joints), (self.runs["jitter_rows"], 7))
        self.assertTrue(self.jitter.has_rates and self.jitter.has_torque)
        self.assertTrue(self.check.uniform)
        resampled = [warning for warning in self.result.warnings if warning.startswith("time steps are not uniform")]
        self.assertEqual(len(resampled), 1, self.result.warnings)
        self.assertIn(f"{self.runs['jitter_repeats']} repeated rows dropped", resampled[0])

    def test_a_labs_log_is_read_with_its_column_map_and_units(self) -> None:
        # The check run as a lab logs it: ';' between fields, time in ms, degrees, columns named by joint.
        with open(self.runs["check"]) as stream:
            rows = [line.strip().split(",") for line in stream if line.strip()]
        header = rows[0]
        keep = ["t"] + [f"q{k}" for k in range(1, 8)] + [f"tau{k}" for k in range(1, 8)]
        index = [header.index(name) for name in keep]
        log = os.path.join(self.directory, "lab_log.csv")
        with open(log, "w") as out:
            out.write(";".join(["time_ms"] + [f"{name}.pos" for name in PANDA_JOINTS] +
                               [f"{name}.eff" for name in PANDA_JOINTS]) + "\n")
            for row in rows[1:]:
                values = [float(row[i]) for i in index]
                values[0] *= 1000.0
                values[1:8] = [math.degrees(v) for v in values[1:8]]
                out.write(";".join(repr(v) for v in values) + "\n")
        with self.assertRaises(ManipidError) as missing:
            self.client.upload_dataset(log)
        self.assertEqual((missing.exception.code, missing.exception.field), ("INVALID_FIELD", "t"))
        self.assertIn("time_ms", str(missing.exception))
        dataset = self.client.upload_dataset(log, columns="time_ms=t,{joint}.pos=q{j},{joint}.eff=tau{j}",
                                             time_unit="ms", angle_unit="deg", robot=self.arm)
        self.assertEqual((dataset.samples, dataset.joints), (self.check.samples, 7))
        stored = [line.split(",") for line in dataset.csv().splitlines()]
        original = [line.split(",") for line in self.check.csv().splitlines()]
        q7, tau7 = stored[0].index("q7"), stored[0].index("tau7")
        for a, b in zip(stored[1:], original[1:]):
            self.assertAlmostEqual(float(a[0]), float(b[0]), delta=1e-12)
            self.assertAlmostEqual(float(a[q7]), float(b[original[0].index("q7")]), delta=1e-12)
            self.assertEqual(float(a[tau7]), float(b[original[0].index("tau7")]))
        with self.assertRaises(TypeError):
            self.client.upload_dataset({"dt": 0.001, "q": [[0.0, 0.1]]}, time_unit="ms")
        dataset.delete()

    def test_a_ros2_bag_is_read_with_its_joints_matched_by_name(self) -> None:
        # The check run as a ROS 2 bag (sqlite3 storage, CDR JointState), the joints in reverse order.
        with open(self.runs["check"]) as stream:
            rows = [line.strip().split(",") for line in stream if line.strip()]
        header = rows[0]

        def cdr(ns: int, names: list, position: list, effort: list) -> bytes:
            body = bytearray()

            def u32(value: int) -> None:
                body.extend(b"\0" * (-len(body) % 4) + struct.pack("<I", value))

            def text(value: str) -> None:
                u32(len(value) + 1)
                body.extend(value.encode() + b"\0")

            def doubles(values: list) -> None:  # CDR aligns an empty sequence's (absent) elements not at all
                u32(len(values))
                if values:
                    body.extend(b"\0" * (-len(body) % 8) + struct.pack(f"<{len(values)}d", *values))

            u32(ns // 10**9)
            u32(ns % 10**9)
            text("world")
            u32(len(names))
            for name in names:
                text(name)
            doubles(position)
            doubles([])
            doubles(effort)
            return b"\0\1\0\0" + bytes(body)

        path = os.path.join(self.directory, "check_0.db3")
        bag = sqlite3.connect(path)
        bag.executescript("CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT, type TEXT, serialization_format TEXT, "
                          "offered_qos_profiles TEXT); CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER, "
                          "timestamp INTEGER, data BLOB); INSERT INTO topics VALUES "
                          "(1, '/joint_states', 'sensor_msgs/msg/JointState', 'cdr', '')")
        joints = list(reversed(range(7)))
        for row in rows[1:]:
            ns = 1_700_000_000 * 10**9 + round(float(row[0]) * 1e9)
            data = cdr(ns, [PANDA_JOINTS[k] for k in joints], [float(row[header.index(f"q{k + 1}")]) for k in joints],
                       [float(row[header.index(f"tau{k + 1}")]) for k in joints])
            bag.execute("INSERT INTO messages(topic_id, timestamp, data) VALUES (1, ?, ?)", (ns, data))
        bag.commit()
        bag.close()
        dataset = self.client.upload_dataset(path, robot=self.arm, name="bagged")
        self.assertEqual((dataset.samples, dataset.joints, dataset.data["name"]), (self.check.samples, 7, "bagged"))
        stored = [line.split(",") for line in dataset.csv().splitlines()]
        original = [line.split(",") for line in self.check.csv().splitlines()]
        for column in ("t", "q1", "q7", "tau2"):
            a, b = stored[0].index(column), original[0].index(column)
            for mine, theirs in zip(stored[1:], original[1:]):
                self.assertAlmostEqual(float(mine[a]), float(theirs[b]), delta=1e-12, msg=column)
        with self.assertRaises(ManipidError) as other:
            self.client.upload_dataset(path, topic="/tf")
        self.assertEqual((other.exception.code, other.exception.field), ("INVALID_FIELD", "topic"))
        dataset.delete()

    def test_identify_sends_a_robot_request(self) -> None:
        request = self.job.data["request"]
        self.assertEqual(request, {"robot_id": self.arm.id, "dataset_id": self.jitter.id,
                                   "validation_dataset_id": self.check.id,
                                   "friction": ["viscous", "coulomb", "offset"]})
        self.assertEqual((self.job.kind, self.job.state, self.job.robot_id),
                         ("robot_identification", "succeeded", self.arm.id))
        # Listed by its kind and its robot; not among the paper's identifications.
        self.assertIn(self.job.id, [job.id for job in self.client.jobs(kind="robot_identification", robot=self.arm)])
        self.assertNotIn(self.job.id, [job.id for job in self.client.jobs(kind="identification")])
        self.assertEqual((self.result.robot_id, self.result.dataset_id), (self.arm.id, self.jitter.id))
        self.assertEqual(self.result["validation_dataset_id"], self.check.id)

    def test_base_parameters_by_name_hold_the_truth(self) -> None:
        base = self.result.base_parameters
        self.assertEqual(len(base), len(self.result["base_parameters"]))
        self.assertEqual(list(base)[:2], ["Izz1 + Iyy2", "mx2"])
        # Friction terms are base parameters of their own; the truth differs from the URDF there.
        for name in ("fv2", "fc2", "fo3"):
            within(self, base[name], self.truth[name], what=name)
        value, std_error = base["fv2"]  # an Estimate is a tuple
        self.assertEqual((value, std_error), (base["fv2"].estimate, base["fv2"].std_error))
        self.assertGreater(abs(value - 0.25), 10 * std_error)  # clearly not the URDF's damping 0.25
        # A combination that holds m3 (3.0 here, 2.5 in the URDF), evaluated at the truth.
        name = next(name for name in base if name.startswith("my2 - 0.316*m3"))
        at_truth = self.result.base_values(self.truth)[name]
        at_urdf = self.result.base_values()[name]
        within(self, base[name], at_truth, what=name)
        self.assertAlmostEqual(at_truth - at_urdf, -0.316 * (self.truth["m3"] - 2.5), places=9)
        self.assertGreater(abs(base[name].estimate - at_urdf), 50 * base[name].std_error)

    def test_friction_point_and_validation_by_name(self) -> None:
        friction = self.result.friction
        self.assertEqual(list(friction), PANDA_JOINTS)
        self.assertEqual(sorted(friction["panda_joint2"]), ["fc", "fo", "fv"])
        self.assertEqual(friction["panda_joint2"]["fv"], self.result.base_parameters["fv2"].estimate)
        point = self.result.point
        self.assertEqual(point["fv2"], friction["panda_joint2"]["fv"])
        self.assertEqual(len(point), 7 * 10 + 3 * 7)  # m mx my mz Ixx..Izz per link, fv fc fo per joint
        self.assertEqual(self.result.prior["m3"], 2.5)
        validation = self.result.validation
        self.assertEqual(len(validation["relative_error"]), 7)
        # The estimate predicts the other run ten times better than the URDF's values do.
        self.assertLess(validation["overall_relative_error"], 0.01)
        self.assertLess(validation["overall_relative_error"], validation["prior"]["overall_relative_error"] / 5)
        self.assertLess(self.result.fit["overall_relative_error"], 0.01)

    def test_fit_and_validation_drawings(self) -> None:
        fit = self.client.fit(self.job, max_points=500)
        self.assertEqual([joint["name"] for joint in fit["joints"]], PANDA_JOINTS)
        self.assertLessEqual(len(fit["t"]), 501)
        self.assertEqual(len(fit["joints"][1]["model"]), len(fit["t"]))
        self.assertEqual(self.job.fit(max_points=500), fit)
        validation = self.client.validation(self.job.id, max_points=300)
        self.assertEqual(len(validation["joints"]), 7)
        self.assertLessEqual(len(validation["t"]), 301)
        self.assertAlmostEqual(validation["overall_relative_error"], self.result.validation["overall_relative_error"],
                               delta=1e-9)
        self.assertIn("prior", validation)
        self.assertEqual(self.job.validation(max_points=300), validation)

    def test_to_urdf_writes_the_estimate(self) -> None:
        # Noise-free data: an estimate whose every body is a real rigid body (a URDF holds no other).
        clean = self.client.upload_dataset(self.runs["clean"])
        job = self.client.identify(clean, robot=self.arm.data, friction="viscous,coulomb,offset")
        result = job.robot_result(timeout=300)
        path = os.path.join(self.directory, "identified.urdf")
        text = self.client.to_urdf(job, path)
        with open(path, "rb") as stream:
            self.assertEqual(stream.read(), text.encode("utf-8"))
        self.assertEqual(job.to_urdf(), text)
        # Before <robot>: where it came from and what the data determine.
        note = re.search(r"<!--\s*(Identified by manipid.*?)-->\s*<robot", text, re.S)
        self.assertIsNotNone(note, text[:2000])
        self.assertIn(f"from 1 run (job {job.id}, dataset {clean.id})", note.group(1))
        self.assertIn(f"of {len(result['base_parameters'])} base parameters", note.group(1))
        # The result's link table: what the URDF holds, link by link.
        self.assertEqual([link["link"] for link in result["links"]], [f"panda_link{k}" for k in range(1, 8)])
        self.assertAlmostEqual(result["links"][1]["mass"], result.point["m2"], delta=1e-12)
        document = ElementTree.fromstring(text)
        self.assertEqual(document.get("name"), "panda_like")
        links = {link.get("name"): link for link in document.iter("link")}
        joints = {joint.get("name"): joint for joint in document.iter("joint")}
        point = result.point
        for k, joint in enumerate(self.arm.joints, start=1):  # body k: the link joint k moves
            mass = links[joint["link"]].find("inertial/mass")
            self.assertAlmostEqual(float(mass.get("value")), point[f"m{k}"], delta=1e-12 * max(1.0, point[f"m{k}"]))
            dynamics = joints[joint["name"]].find("dynamics")
            self.assertAlmostEqual(float(dynamics.get("damping")), point[f"fv{k}"], delta=1e-12)
            self.assertAlmostEqual(float(dynamics.get("friction")), point[f"fc{k}"], delta=1e-12)
        self.assertNotAlmostEqual(point["m3"], 2.5, delta=1e-3)  # the estimate, not the URDF's mass
        within(self, result.base_parameters["fv2"], self.truth["fv2"], what="fv2 (noise-free)")

    def test_design_excitation_and_its_trajectory(self) -> None:
        job = self.client.design_excitation(self.arm, period=2, harmonics=3, duration=4, max_seconds=5,
                                            name="short excitation", friction="viscous,coulomb")
        self.assertIsInstance(job, Job)
        self.assertEqual((job.kind, job.robot_id), ("excitation", self.arm.id))
        self.assertEqual(job.data["request"], {"robot_id": self.arm.id, "period": 2, "harmonics": 3, "duration": 4,
                                               "max_seconds": 5, "name": "short excitation",
                                               "friction": ["viscous", "coulomb"]})
        path = os.path.join(self.directory, "designed.csv")
        trajectory = self.client.excitation_trajectory(job, path=path, timeout=120)
        result = job.result()
        self.assertGreater(result["condition_number"], 1.0)
        self.assertEqual(result["coefficients"]["harmonics"], 3)
        self.assertEqual(sorted(trajectory), ["q", "qd", "qdd", "t"])
        self.assertEqual(len(trajectory["t"]), 4001)  # two whole periods every 1 ms
        self.assertAlmostEqual(trajectory["t"][-1], 4.0, delta=1e-12)
        for block in ("q", "qd", "qdd"):
            self.assertEqual([len(joint) for joint in trajectory[block]], [4001] * 7)
        for joint, spec in zip(range(7), self.arm.joints):  # at rest at both ends, within the limits
            self.assertEqual((trajectory["qd"][joint][0], trajectory["qd"][joint][-1]), (0.0, 0.0))
            self.assertEqual((trajectory["qdd"][joint][0], trajectory["qdd"][joint][-1]), (0.0, 0.0))
            self.assertGreaterEqual(min(trajectory["q"][joint]), spec["limits"]["lower"])
            self.assertLessEqual(max(trajectory["q"][joint]), spec["limits"]["upper"])
        dataset = self.client.dataset(job.dataset_id)
        self.assertEqual((dataset.name, dataset.source_job, dataset.has_rates, dataset.has_torque),
                         ("short excitation", job.id, True, False))
        with open(path) as stream:
            lines = stream.read().splitlines()
        self.assertEqual(len(lines), 4002)
        self.assertEqual(lines[0], ",".join(["t"] + [f"{b}{k}" for b in ("q", "qd", "qdd") for k in range(1, 8)]))
        thinned = self.client.excitation_trajectory(job.data, max_points=100)["t"]  # about 100, the first and the last
        self.assertTrue(90 <= len(thinned) <= 100 and thinned[0] == 0.0 and thinned[-1] == trajectory["t"][-1], thinned)

    def test_friction_as_text_and_none(self) -> None:
        job = self.client.identify(self.check, robot=self.arm, friction="none", trim=(0.5, 0.5), weights="per-joint")
        self.assertEqual(job.data["request"], {"robot_id": self.arm.id, "dataset_id": self.check.id, "friction": [],
                                               "trim": [0.5, 0.5], "weights": "per-joint"})
        result = job.robot_result(timeout=300)
        self.assertEqual(result["parameters"]["friction"], [])
        self.assertFalse([name for name in result.base_parameters if name[:2] in ("fv", "fc", "fo")])
        self.assertEqual(result.friction, {joint: {} for joint in PANDA_JOINTS})

    def test_several_runs_and_the_held_out_options(self) -> None:
        job = self.client.identify([self.jitter, self.check], robot=self.arm, validate=[self.check], friction="auto",
                                   judge_cutoff=4, torque_joints=range(1, 7))
        self.assertEqual(job.data["request"], {"robot_id": self.arm.id, "dataset_ids": [self.jitter.id, self.check.id],
                                               "validation_dataset_ids": [self.check.id], "friction": "auto",
                                               "judge_cutoff": 4, "torque_joints": [1, 2, 3, 4, 5, 6]})
        result = job.robot_result(timeout=300)
        self.assertEqual(result["runs"], 2)
        self.assertEqual(result.judge["cutoff_hz"], 4)
        self.assertEqual(result.torque_joints, PANDA_JOINTS[:6])
        self.assertEqual(len(result.validation["relative_error"]), 6)
        self.assertTrue(result.selection["by_held_out"])
        self.assertTrue(all(0.0 <= share <= 1.0 for share in result.data_share.values()))
        with self.assertRaises(TypeError):
            self.client.identify([self.jitter, self.check])  # several runs are for a robot

    # --- errors ----------------------------------------------------------------------------
    def test_unknown_robot(self) -> None:
        with self.assertRaises(ManipidError) as caught:
            self.client.identify(self.jitter, robot="rb_0000000000000000")
        error = caught.exception
        self.assertEqual((error.status, error.code, error.field), (422, "INVALID_FIELD", "robot_id"))
        self.assertIn("rb_0000000000000000", error.detail)
        with self.assertRaises(ManipidError) as caught:
            self.client.robot("rb_0000000000000000")
        self.assertEqual((caught.exception.status, caught.exception.code), (404, "NOT_FOUND"))
        with self.assertRaises(ManipidError) as caught:
            self.client.design_excitation("rb_0000000000000000")
        self.assertEqual((caught.exception.status, caught.exception.field), (422, "robot_id"))

    def test_datasets_that_do_not_fit_the_robot(self) -> None:
        ur5 = self.client.upload_robot(UR5)
        with self.assertRaises(ManipidError) as caught:
            self.client.identify(self.jitter, robot=ur5)
        error = caught.exception
        self.assertEqual((error.status, error.code, error.field), (422, "INVALID_FIELD", "dataset_id"))
        self.assertIn("7 joints", error.detail)
        self.assertIn("6", error.detail)
        no_torque = self.client.upload_dataset({"dt": 0.001, "q": [[0.0, 0.1, 0.2]] * 7})
        with self.assertRaises(ManipidError) as caught:
            self.client.identify(self.jitter, robot=self.arm, validate=no_torque)
        self.assertEqual((caught.exception.status, caught.exception.field), (422, "validation_dataset_id"))

    def test_options_of_the_wrong_kind(self) -> None:
        with self.assertRaises(ManipidError) as caught:  # a preset option with a robot
            self.client.identify(self.jitter, robot=self.arm, method="two-stage")
        self.assertEqual((caught.exception.status, caught.exception.field), (422, "method"))
        with self.assertRaises(ManipidError) as caught:
            self.client.identify(self.jitter, robot=self.arm, friction=["viscous", "stiction"])
        self.assertEqual((caught.exception.status, caught.exception.field), (422, "friction"))
        with self.assertRaises(TypeError):  # checked here: nothing is sent
            self.client.identify(self.jitter, validate=self.check)

    # --- payloads --------------------------------------------------------------------------
    def test_a_tool_on_the_identified_arm(self) -> None:
        tool = self.client.upload_dataset(self.runs["tool"], name="with the tool")
        truth = self.runs["tool_truth"]
        job = self.client.identify_payload(tool, self.arm, arm=self.job, validate=tool, judge_trim=0.25, physical=True)
        self.assertEqual(job.kind, "payload_identification")
        self.assertEqual(job.robot_id, self.arm.id)
        result = job.wait(timeout=300)
        self.assertTrue(result["detected"], result["warnings"])
        self.assertEqual(result["arm_job_id"], self.job.id)
        # The arm as identified from the jittery run without the tool: the payload within 3 % and 5 mm.
        self.assertLess(abs(result["mass"] - truth["mass"]), 0.03 * truth["mass"], result["mass"])
        self.assertLess(math.dist(result["centre_of_mass"], truth["centre_of_mass"]), 5e-3, result["centre_of_mass"])
        self.assertGreater(result["mass_std_error"], 0.0)
        self.assertEqual(result["judge"]["trim_seconds"], 0.25)
        self.assertTrue(result["consistent"] and result["physical"] is not None, result["physical"])
        self.assertEqual(job.refresh().data["request"]["physical"], True)
        # The torque with and without the tool, and the URDF with the tool mounted on the tip link.
        fit = job.fit(max_points=200)
        self.assertEqual(len(fit["joints"]), 7)
        self.assertEqual(len(fit["joints"][6]["arm_only"]), len(fit["t"]))
        self.assertLess(fit["overall_relative_error"], fit["arm_only"]["overall_relative_error"] / 2)
        self.assertEqual(job.validation(max_points=200)["arm_only"], fit["arm_only"])  # the same run
        document = ElementTree.fromstring(job.to_urdf())
        mounted = {link.get("name"): link for link in document.iter("link")}["manipid_payload"]
        self.assertAlmostEqual(float(mounted.find("inertial/mass").get("value")), result["mass"], delta=1e-6)
        # A run of the arm without the tool: no payload, not an error.
        none = self.client.identify_payload(self.jitter, self.arm.id, arm=self.job.id, known_centre_of_mass=[0, 0, 0.05])
        empty = none.wait(timeout=300)
        self.assertFalse(empty["detected"], empty)
        self.assertLess(abs(empty["mass"]), 3 * empty["mass_std_error"])

    def test_a_payload_refused_names_its_field(self) -> None:
        tool = self.client.upload_dataset(self.runs["tool"])
        for kwargs, field in (({"arm": "job_0000000000000000"}, "arm_job_id"), ({"known_mass": 0}, "known_mass"),
                              ({"known_centre_of_mass": [0, 0]}, "known_centre_of_mass"),
                              ({"friction": ["viscous"]}, "friction")):
            with self.assertRaises(ManipidError) as caught:
                self.client.identify_payload(tool, self.arm, **kwargs)
            self.assertEqual((caught.exception.status, caught.exception.field), (422, field), kwargs)
        preset = self.client.simulate(duration=0.2)
        preset.wait(timeout=300)
        with self.assertRaises(ManipidError) as caught:  # not an identification of the arm
            self.client.identify_payload(tool, self.arm, arm=preset)
        self.assertEqual(caught.exception.field, "arm_job_id")
        self.assertIn("not a robot_identification", caught.exception.detail)

    def test_drawings_and_urdf_of_jobs_that_have_none(self) -> None:
        preset = self.client.identify(None, simulation={"duration": 2}, half_length=100, band=0.2)
        preset.wait(timeout=300)
        with self.assertRaises(ManipidError) as caught:  # the paper's preset: no URDF to write into
            self.client.to_urdf(preset)
        self.assertEqual((caught.exception.status, caught.exception.code), (409, "CONFLICT"))
        no_validation = self.client.identify(self.check, robot=self.arm)
        no_validation.wait(timeout=300)
        with self.assertRaises(ManipidError) as caught:
            self.client.validation(no_validation)
        self.assertEqual((caught.exception.status, caught.exception.code), (409, "CONFLICT"))
        with self.assertRaises(ManipidError) as caught:
            self.client.to_urdf("job_0000000000000000")
        self.assertEqual((caught.exception.status, caught.exception.code), (404, "NOT_FOUND"))


@unittest.skipUnless(BINARY, "no manipid binary: set MANIPID_BIN or build build/release")
class ReadmeYourOwnRobot(unittest.TestCase):
    def test_readme_example_verbatim(self) -> None:
        """The README's "Your own robot" section as printed: its shell lines, then its Python."""
        readme = (PACKAGE_ROOT / "README.md").read_text(encoding="utf-8")
        section = re.search(r"## Your own robot\n(.*?)\n## ", readme, re.S).group(1)
        blocks = re.findall(r"```(python|sh)\n(.*?)```", section, re.S)
        self.assertEqual([kind for kind, _ in blocks], ["python", "sh", "python"])
        with tempfile.TemporaryDirectory(prefix="manipid-readme-robot-") as directory:
            (Path(directory) / "examples" / "robots").mkdir(parents=True)
            shutil.copy(PANDA, Path(directory) / "examples" / "robots")
            bin_directory = Path(directory) / "bin"
            bin_directory.mkdir()
            (bin_directory / "manipid").symlink_to(BINARY)
            environment = dict(os.environ, PYTHONPATH=str(PACKAGE_ROOT), MANIPID_BIN=BINARY,
                               PATH=f"{bin_directory}{os.pathsep}{os.environ.get('PATH', '')}")
            outputs = []
            for kind, code in blocks:
                command = [sys.executable, "-c", code] if kind == "python" else ["bash", "-euo", "pipefail", "-c", code]
                done = subprocess.run(command, cwd=directory, env=environment, capture_output=True, text=True,
                                      timeout=300)
                self.assertEqual(done.returncode, 0, f"{kind} block failed:\n{code}\n{done.stderr}")
                outputs.append(done.stdout)
            identified = (Path(directory) / "panda_identified.urdf").read_text(encoding="utf-8")
        design, _, identification = outputs
        self.assertRegex(design.strip(), r"^condition number \d+\.\d+, 20001 samples$")
        lines = identification.strip().splitlines()
        self.assertRegex(lines[0], r"^fv2 +0\.(39|40)\d\d ± \d\.\de-\d\d$")  # the arm's 0.4, not the URDF's 0.25
        self.assertRegex(lines[1], r"^\{'fv': 0\.(39|40)\d*, 'fc': 0\.(69|70)\d*\}$")
        match = re.fullmatch(r"validation: (\d+\.\d\d)% of the torque \(the URDF's own values: (\d+\.\d\d)%\)", lines[-1])
        self.assertIsNotNone(match, lines[-1])
        self.assertLess(float(match.group(1)), float(match.group(2)) / 10)
        ElementTree.fromstring(identified)


class WithoutServer(unittest.TestCase):
    def test_base_value_reads_the_printed_combinations(self) -> None:
        values = {"Izz2": 1.0, "m3": 2.0, "mz3": 0.5, "Iyy3": 0.25, "fv1": 3.0}
        self.assertEqual(base_value("fv1", values), 3.0)
        self.assertAlmostEqual(base_value("Izz2 + 0.099856*m3 + 0.632*mz3 + Iyy3", values),
                               1.0 + 0.099856 * 2.0 + 0.632 * 0.5 + 0.25, places=12)
        self.assertAlmostEqual(base_value("Izz2 - 1e-05*m3 - mz3", values), 1.0 - 2e-5 - 0.5, places=12)
        for bad in ("", "Izz2 +", "Izz2 Iyy3", "2*"):
            with self.assertRaises(ValueError):
                base_value(bad, values)
        with self.assertRaises(ValueError):
            base_value("Izz2 + m4", values)

    def test_robot_result_from_json(self) -> None:
        result = RobotResult({
            "base_parameters": [{"name": "fv1", "estimate": 0.3, "std_error": 0.01},
                                {"name": "Izz1 + 0.5*m2", "estimate": 1.5, "std_error": None}],
            "friction": [{"joint": "j1", "fv": 0.3}], "point": {"fv1": 0.3, "Izz1": 1.0, "m2": 1.0},
            "prior": {"fv1": 0.2, "Izz1": 1.0, "m2": 2.0}})
        self.assertEqual(result.base_parameters, {"fv1": Estimate(0.3, 0.01), "Izz1 + 0.5*m2": Estimate(1.5, None)})
        self.assertEqual(result.friction, {"j1": {"fv": 0.3}})
        self.assertEqual(result.base_values(), {"fv1": 0.2, "Izz1 + 0.5*m2": 2.0})
        self.assertEqual(result.base_values({"m2": 4.0})["Izz1 + 0.5*m2"], 3.0)
        self.assertIsNone(result.validation)
        self.assertEqual(result["point"]["m2"], 1.0)
        with self.assertRaises(ValueError):
            RobotResult({"estimates": {"m2": 25.0}})  # a preset result

    def test_bad_arguments(self) -> None:
        client = Client("http://127.0.0.1:9")
        with self.assertRaises(TypeError):
            client.identify("ds_x", validate="ds_y")  # validate needs robot=
        with self.assertRaises(TypeError):
            client.identify("ds_x", robot="rb_x", robot_id="rb_y")
        with self.assertRaises(ValueError):
            client.upload_robot("<robot/>", form="yaml")
        with self.assertRaises(TypeError):
            client.upload_robot(42)


if __name__ == "__main__":
    unittest.main()
