"""dataset_limits_test.py — hostile-client suite: what the validator accepts, the store must
hold (item 8 of the hardening issue), against the real `manipid serve` on port 0.

One owner for a dataset's size (api/include/manipid/api/limits.h): at most 200 joints for a
JSON upload, a CSV upload and a robot alike, and at most 100,000,000 numbers in one dataset
(SQLite refuses a row over 1e9 bytes), checked at the door — a simulation whose
duration / dt would give more is refused with the field named, before anything runs. A
dataset at the joint limit exports as CSV and reads back.

Run: MANIPID_BIN=build/debug/server/manipid python3 tests/hostile/dataset_limits_test.py -v
"""
import os
import sys
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "service"))
from harness import SharedServerTestCase  # noqa: E402

MAX_JOINTS = 200


def dataset(joints, samples=3, blocks=("q", "tau", "ref", "qd", "qdd")):
    body = {"dt": 0.01}
    for index, block in enumerate(blocks):
        body[block] = [[0.001 * (joint + 1) + 0.1 * sample + index for sample in range(samples)]
                       for joint in range(joints)]
    return body


def chain_urdf(joints):
    links = "".join(f'<link name="l{k}"><inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" '
                    f'iyy="0.01" iyz="0" izz="0.01"/></inertial></link>' for k in range(joints + 1))
    chain = "".join(f'<joint name="j{k}" type="revolute"><parent link="l{k}"/><child link="l{k + 1}"/>'
                    f'<origin xyz="0 0 0.1"/><axis xyz="0 0 1"/>'
                    f'<limit lower="-3" upper="3" effort="100" velocity="2"/></joint>' for k in range(joints))
    return f'<robot name="long">{links}{chain}</robot>'


class DatasetLimits(SharedServerTestCase):
    def assert_refused(self, method, path, body, field, words, headers=None):
        status, answer_headers, problem = self.server.request(method, path, body, headers)
        self.assertEqual(status, 422, problem)
        self.assertEqual(answer_headers["content-type"], "application/problem+json")
        self.assertEqual(problem["code"], "INVALID_FIELD")
        self.assertEqual(problem["field"], field)
        self.assertIn(words, problem["detail"])
        self.assertLess(len(problem["detail"]), 200)

    def count_jobs(self):
        return len(self.server.request("GET", "/v1/jobs?page_size=1000")[2]["items"])

    def test_a_simulation_the_store_cannot_hold_is_refused_at_the_door(self):
        # 9,990,001 samples (under the 10 M sample cap) of t, q, tau and ref for 4 joints: 129,870,013
        # numbers, 1.04 GB — SQLite's "string or blob too big" after minutes of work, before.
        before = self.count_jobs()
        self.assert_refused("POST", "/v1/simulations", {"duration": 999, "dt": 1e-4}, "dt",
                            "duration / dt gives 9990001 samples of 13 numbers (129870013); a dataset holds at most "
                            "100000000, 7692307 such samples")
        self.assert_refused("POST", "/v1/identifications", {"simulation": {"duration": 999, "dt": 1e-4}},
                            "simulation.dt", "a dataset holds at most 100000000")
        # Past the sample cap itself, with the preset's dt, the duration is at fault.
        self.assert_refused("POST", "/v1/identifications", {"simulation": {"duration": 1e5}},
                            "simulation.duration", "simulation.duration must be in (0, 3600] s")
        self.assertEqual(self.count_jobs(), before)  # nothing was queued

    def test_more_joints_than_the_limit_are_refused_in_json(self):
        # The 2,000-joint upload was accepted, and its own CSV export refused on re-upload.
        self.assert_refused("POST", "/v1/datasets", dataset(2000, samples=2, blocks=("q",)), "q",
                            "q has 2000 joints; at most 200 are allowed")
        self.assert_refused("POST", "/v1/datasets", dataset(MAX_JOINTS + 1, samples=2, blocks=("q",)), "q",
                            "q has 201 joints; at most 200 are allowed")

    def test_more_joints_than_the_limit_are_refused_in_csv(self):
        header = ",".join(["t"] + [f"q{k}" for k in range(1, MAX_JOINTS + 2)])
        rows = "\n".join(",".join([str(0.1 * i)] + ["0.5"] * (MAX_JOINTS + 1)) for i in range(3))
        self.assert_refused("POST", "/v1/datasets", header + "\n" + rows + "\n", "q201",
                            "the CSV has 201 joints; at most 200 are allowed", {"Content-Type": "text/csv"})

    def test_a_robot_with_more_joints_than_the_limit_is_refused(self):
        # A stored robot's own, lower limit (tests/hostile/urdf_test.py: its base parameters cost joints³).
        self.assert_refused("POST", "/v1/robots", chain_urdf(MAX_JOINTS + 1), "urdf",
                            "the URDF chain has 201 moving joints; the service takes chains of at most 50",
                            {"Content-Type": "application/xml"})

    def test_a_dataset_at_the_joint_limit_exports_as_csv_and_reads_back(self):
        body = dataset(MAX_JOINTS)
        status, _, created = self.server.request("POST", "/v1/datasets", body)
        self.assertEqual(status, 201, created)
        self.assertEqual(created["joints"], MAX_JOINTS)
        status, headers, text = self.server.request("GET", f"/v1/datasets/{created['id']}/data?format=csv")
        self.assertEqual(status, 200)
        self.assertTrue(headers["content-type"].startswith("text/csv"))
        header = text.splitlines()[0].split(",")
        self.assertEqual(len(header), 1 + 5 * MAX_JOINTS)  # t and five blocks of 200
        status, _, again = self.server.request("POST", "/v1/datasets", text, {"Content-Type": "text/csv"})
        self.assertEqual(status, 201, again)
        self.assertEqual(again["joints"], MAX_JOINTS)
        self.assertEqual(again["samples"], 3)
        status, _, data = self.server.request("GET", f"/v1/datasets/{again['id']}/data")
        self.assertEqual(status, 200)
        for block in ("q", "tau", "ref", "qd", "qdd"):
            self.assertEqual(data[block], body[block], block)


if __name__ == "__main__":
    unittest.main()
