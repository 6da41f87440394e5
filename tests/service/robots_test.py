"""robots_test.py — a lab's own arm through the service alone, against the real binary on port 0: upload
a 7-joint URDF, design an excitation, "run" it (the real `manipid torque` with known parameters, logged
at jittery time steps with stale repeats), upload, identify with friction and validation, check the
estimate's torque at random states against the truth, write the identified URDF back and check it
reproduces the estimate; and every bad input refused with problem+json, nothing stored.

Run: MANIPID_BIN=build/debug/server/manipid python3 tests/service/robots_test.py -v
"""
import csv
import io
import json
import math
import os
import random
import subprocess
import sys
import unittest

sys.path.insert(0, os.path.dirname(__file__))
from harness import Server, binary, temporary_directory  # noqa: E402

SOURCE = os.path.join(os.path.dirname(__file__), "..", "..")
PANDA = os.path.join(SOURCE, "examples", "robots", "panda_like.urdf")
UR5 = os.path.join(SOURCE, "examples", "robots", "ur5_like.urdf")


def read_csv(text):
    rows = list(csv.reader(io.StringIO(text)))
    return rows[0], [[float(v) for v in row] for row in rows[1:]]


def write_csv(path, header, rows):
    with open(path, "w") as stream:
        stream.write(",".join(header) + "\n")
        for row in rows:
            stream.write(",".join(repr(v) for v in row) + "\n")


def torque(urdf, states, out, *extra):
    subprocess.run([binary(), "torque", "--robot", urdf, "--in", states, "--out", out, *extra], check=True,
                   stderr=subprocess.DEVNULL)
    with open(out) as stream:
        return read_csv(stream.read())


class RobotThroughTheService(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.directory = temporary_directory()
        cls.dir = cls.directory.name
        cls.server = Server(os.path.join(cls.dir, "jobs.db")).start()

    @classmethod
    def tearDownClass(cls):
        status = cls.server.stop()
        cls.directory.cleanup()
        assert status == 0, status

    def path(self, name):
        return os.path.join(self.dir, name)

    def post(self, path, body, headers=None, expected=(200, 201, 202)):
        status, answer_headers, answer = self.server.request("POST", path, body, headers)
        self.assertIn(status, expected if isinstance(expected, tuple) else (expected,), answer)
        return answer

    def upload_robot(self, urdf_path, name=None):
        with open(urdf_path, "rb") as stream:
            document = stream.read()
        query = f"?name={name}" if name else ""
        robot = self.post("/v1/robots" + query, document, {"Content-Type": "application/xml"}, 201)
        return robot, document

    def excitation_csv(self, robot, dt, seed, name):
        """Designed by the service, downloaded as CSV (t, q, qd, qdd), resampled to `dt` by the CLI."""
        job = self.post("/v1/excitations", {"robot_id": robot["id"], "period": 10, "harmonics": 5, "duration": 10,
                                            "dt": dt, "seed": seed, "max_evaluations": 150, "max_seconds": 600})
        job = self.server.wait_job(job["id"])
        self.assertEqual(job["state"], "succeeded", job)
        # The budget is evaluations, not seconds (the time limit is far above what 150 take, even
        # under ASan on a loaded machine): the same design on any machine; the finished job says how many.
        coefficients = job["result"]["coefficients"]
        self.assertEqual(coefficients["termination"], "max_evaluations", coefficients["message"])
        self.assertEqual(coefficients["evaluations"], 150)
        self.assertEqual(job["progress"]["evaluations"], 150)
        status, _, text = self.server.request("GET", f"/v1/datasets/{job['result']['dataset_id']}?format=csv")
        self.assertEqual(status, 200)
        with open(self.path(name), "w") as stream:
            stream.write(text)
        return job

    def test_a_seven_joint_arm_from_urdf_to_identified_urdf(self):
        robot, document = self.upload_robot(PANDA, "panda")
        self.assertTrue(robot["id"].startswith("rb_"))
        self.assertEqual(len(robot["joints"]), 7)
        self.assertEqual(robot["joints"][6]["body_links"], ["panda_link7", "panda_link8"])  # the flange merged
        self.assertEqual(robot["links"]["self"], f"/v1/robots/{robot['id']}")
        self.assertEqual(robot["base_parameters"]["count"], 57)
        status, headers, back = self.server.request("GET", f"/v1/robots/{robot['id']}?format=urdf")
        self.assertEqual(status, 200)
        self.assertEqual(back.encode(), document)  # byte for byte

        # The truth: the URDF's values moved by up to ±15 %, friction and offsets of plausible size.
        names = robot["parameters"]["names"]
        values = robot["parameters"]["urdf_values"]
        # Each body scaled as a whole (mass, first moments, inertia alike), so the truth stays a physical body.
        rng = random.Random(5)
        scale = {k: 1 + 0.15 * rng.uniform(-1, 1) for k in range(1, 8)}
        truth = {name: values[name] * scale[int(name.lstrip("mxyzI")[-1])] for name in names if not name.startswith("f")}
        for k in range(1, 8):
            truth[f"fv{k}"] = rng.uniform(0.2, 1.0)
            truth[f"fc{k}"] = rng.uniform(0.5, 2.0)
        with open(self.path("truth.json"), "w") as stream:
            json.dump(truth, stream)

        # Run the excitation at 0.5 ms and "log" it at jittery steps with stale repeats.
        self.excitation_csv(robot, 0.0005, 1, "excitation.csv")
        header, rows = torque(PANDA, self.path("excitation.csv"), self.path("run_fine.csv"), "--with-states",
                              "--params", self.path("truth.json"))
        logged = []
        step = random.Random(3)
        i = 0
        while i < len(rows):
            logged.append(rows[i])
            if len(logged) % 25 == 0:  # the logger missed a sample: the last row again, new time stamp
                stale = list(rows[i])
                stale[0] = rows[min(i + 1, len(rows) - 1)][0]
                logged.append(stale)
                i += 1
            i += step.choice([1, 2, 2, 2, 3]) if len(logged) % 997 else 18  # 0.5–1.5 ms, and a 9 ms gap
        write_csv(self.path("run.csv"), header, logged)
        with open(self.path("run.csv")) as stream:
            run = self.post("/v1/datasets?name=run", stream.read(), {"Content-Type": "text/csv"}, 201)
        self.assertFalse(run["uniform"])
        self.assertTrue(run["has_rates"])

        # A second run for validation: another excitation, logged uniformly.
        self.excitation_csv(robot, 0.001, 2, "excitation2.csv")
        torque(PANDA, self.path("excitation2.csv"), self.path("run2.csv"), "--with-states", "--params",
               self.path("truth.json"))
        with open(self.path("run2.csv")) as stream:
            second = self.post("/v1/datasets?name=run2", stream.read(), {"Content-Type": "text/csv"}, 201)

        job = self.post("/v1/identifications", {"robot_id": robot["id"], "dataset_id": run["id"],
                                                "validation_dataset_id": second["id"], "friction": ["viscous", "coulomb"],
                                                "physical": True})
        self.assertEqual(job["robot_id"], robot["id"])
        self.assertEqual(job["kind"], "robot_identification")
        job = self.server.wait_job(job["id"])
        self.assertEqual(job["state"], "succeeded", job)
        # Listed under its own kind (and its robot's), not among the paper's identifications.
        for query, listed in ((f"kind=robot_identification&robot_id={robot['id']}", True), ("kind=robot_identification", True),
                              ("kind=identification", False), (f"robot_id={robot['id']}", True)):
            status, _, page = self.server.request("GET", "/v1/jobs?" + query)
            self.assertEqual(status, 200, page)
            self.assertEqual(job["id"] in [item["id"] for item in page["items"]], listed, query)
        result = job["result"]
        self.assertEqual(len(result["base_parameters"]), 57)  # 43 inertial + 14 friction (viscous, Coulomb)
        # Each base parameter is its combination of the point's standard parameters, in full precision.
        for base in result["base_parameters"]:
            value = sum(coefficient * result["point"][name] for name, coefficient in base["combination"].items())
            self.assertLess(abs(value - base["estimate"]), 1e-9 * (1 + abs(base["estimate"])), base["name"])
        self.assertTrue(any("repeated rows dropped" in warning for warning in result["warnings"]), result["warnings"])
        self.assertTrue(result["consistency"]["consistent"], result["consistency"]["findings"])
        self.assertTrue(result["physical"]["converged"], result["physical"])
        self.assertLess(result["validation"]["overall_relative_error"], 0.01)
        self.assertGreater(result["validation"]["prior"]["overall_relative_error"],
                           10 * result["validation"]["overall_relative_error"])

        # The estimate's torque at random states within the joint limits, beside the truth's.
        limits = [joint["limits"] for joint in robot["joints"]]
        states = random.Random(9)
        state_rows = []
        for _ in range(300):
            q = [states.uniform(l["lower"], l["upper"]) for l in limits]
            state_rows.append(q + [states.gauss(0, 1) for _ in range(7)] + [states.gauss(0, 1) for _ in range(7)])
        write_csv(self.path("states.csv"), [f"{p}{k}" for p in ("q", "qd", "qdd") for k in range(1, 8)], state_rows)
        with open(self.path("result.json"), "w") as stream:
            json.dump(result, stream)
        _, estimated = torque(PANDA, self.path("states.csv"), self.path("tau_estimate.csv"), "--params", self.path("result.json"))
        _, true = torque(PANDA, self.path("states.csv"), self.path("tau_truth.csv"), "--params", self.path("truth.json"))
        difference = sum((a - b) ** 2 for row_a, row_b in zip(estimated, true) for a, b in zip(row_a, row_b))
        size = sum(b ** 2 for row in true for b in row)
        # The CLI's bound for a jittery 7-joint log with Coulomb friction (tests/core/robot/identification_test.cpp).
        self.assertLess(math.sqrt(difference / size), 5e-3)

        # The identified URDF: parses, and reproduces the estimate's torques.
        status, headers, identified = self.server.request("GET", f"/v1/jobs/{job['id']}/urdf")
        self.assertEqual(status, 200, identified)
        self.assertIn("identified.urdf", headers["content-disposition"])
        with open(self.path("identified.urdf"), "w") as stream:
            stream.write(identified)
        _, by_urdf = torque(self.path("identified.urdf"), self.path("states.csv"), self.path("tau_urdf.csv"))
        worst = max(abs(a - b) / (1 + abs(b)) for row_a, row_b in zip(by_urdf, estimated) for a, b in zip(row_a, row_b))
        self.assertLess(worst, 1e-9)

    def test_bad_input_is_refused_and_nothing_is_stored(self):
        _, _, before = self.server.request("GET", "/v1/robots?page_size=1000")
        status, _, problem = self.server.request("POST", "/v1/robots", "<robot name='x'><link name='a'>",
                                                 {"Content-Type": "application/xml"})
        self.assertEqual(status, 422, problem)
        self.assertEqual(problem["field"], "urdf")
        status, _, problem = self.server.request("POST", "/v1/robots", {"urdf": "<robot name='x'/>", "tip": "nowhere"})
        self.assertEqual(status, 422, problem)
        _, _, after = self.server.request("GET", "/v1/robots?page_size=1000")
        self.assertEqual(len(after["items"]), len(before["items"]))

        ur5, _ = self.upload_robot(UR5)
        # A 4-joint dataset for a 6-joint robot: 422 naming both counts.
        dataset = self.post("/v1/datasets", {"dt": 0.001, "q": [[0.0] * 50] * 4, "tau": [[0.0] * 50] * 4}, None, 201)
        status, _, problem = self.server.request("POST", "/v1/identifications",
                                                 {"robot_id": ur5["id"], "dataset_id": dataset["id"]})
        self.assertEqual(status, 422, problem)
        self.assertEqual(problem["field"], "dataset_id")
        self.assertIn("4 joints, the robot ur5_like has 6", problem["detail"])
        status, _, problem = self.server.request("POST", "/v1/identifications",
                                                 {"robot_id": "rb_0000000000000000", "dataset_id": dataset["id"]})
        self.assertEqual(status, 422, problem)
        self.assertEqual(problem["field"], "robot_id")
        status, _, problem = self.server.request("POST", "/v1/identifications",
                                                 {"robot_id": ur5["id"], "dataset_id": dataset["id"], "method": "two-stage"})
        self.assertEqual(status, 422, problem)
        self.assertIn("paper's preset model", problem["detail"])
        status, _, problem = self.server.request("POST", "/v1/excitations", {"robot_id": ur5["id"], "harmonics": 1})
        self.assertEqual(status, 422, problem)
        self.assertEqual(problem["field"], "harmonics")
        # A lab's limits are checked against the robot at submission, each naming its field.
        for body, field, words in [
                ({"start_pose": [0, 0]}, "start_pose", "one value per joint (6), got 2"),
                ({"start_pose": [0, 0, 9, 0, 0, 0]}, "start_pose", "outside its URDF limits"),
                ({"max_torque": [1, 2]}, "max_torque", "1 value or one per joint (6), got 2"),
                ({"max_jerk": -1}, "max_jerk", "positive"),
                ({"torque_parameters": {"m99": 1}}, "torque_parameters", "m99"),
                ({"moving_joints": [4, 7]}, "moving_joints", "joint 7 is not one of the robot's 6"),
                ({"moving_joints": []}, "moving_joints", "array of joint numbers"),
                ({"target": "tool"}, "target", "payload")]:
            status, _, problem = self.server.request("POST", "/v1/excitations", {"robot_id": ur5["id"], **body})
            self.assertEqual(status, 422, (body, problem))
            self.assertEqual(problem["field"], field, problem)
            self.assertIn(words, problem["detail"])

        # Where the arm stands, torque held below the URDF's efforts: the dataset ramps from the pose
        # and back, and the result carries the predicted torque within its limits.
        pose = [0.0, -1.0, 1.0, -1.0, 0.5, 0.0]
        job = self.server.wait_job(self.post("/v1/excitations", {
            "robot_id": ur5["id"], "period": 5, "harmonics": 3, "dt": 0.01, "max_evaluations": 40, "max_seconds": 600,
            "start_pose": pose, "max_torque": 100, "max_velocity": [1, 1, 1, 2, 2, 2]})["id"])
        self.assertEqual(job["state"], "succeeded", job)
        result = job["result"]
        self.assertGreater(result["ramp_duration"], 0)
        data = self.server.request("GET", f"/v1/datasets/{result['dataset_id']}/data")[2]
        self.assertEqual([q[0] for q in data["q"]], pose)
        self.assertEqual([q[-1] for q in data["q"]], pose)
        self.assertAlmostEqual(data["t"][-1], 5 + 2 * result["ramp_duration"], places=9)
        self.assertLessEqual(max(abs(v) for v in data["qd"][0]), 1.0)
        limits = result["coefficients"]["limits"]
        self.assertEqual(limits["torque"], [100, 100, 100, 28, 28, 28])
        self.assertEqual(len(result["torque"]["tau"]), 6)
        for tau, limit in zip(result["torque"]["tau"], limits["torque"]):
            self.assertLessEqual(max(abs(value) for value in tau), limit)

        # A payload's excitation: the wrist alone, a few seconds; the other joints hold still.
        job = self.server.wait_job(self.post("/v1/excitations", {
            "robot_id": ur5["id"], "target": "payload", "moving_joints": [4, 5, 6], "period": 4, "harmonics": 3,
            "dt": 0.01, "max_evaluations": 60, "max_seconds": 600})["id"])
        self.assertEqual(job["state"], "succeeded", job)
        coefficients = job["result"]["coefficients"]
        self.assertEqual(coefficients["target"], "payload")
        self.assertEqual(coefficients["base_parameters"], 10)
        self.assertEqual(len(coefficients["moving_joints"]), 3)
        for k in range(3):
            self.assertEqual(max(abs(v) for v in coefficients["a"][k] + coefficients["b"][k]), 0.0)
        data = self.server.request("GET", f"/v1/datasets/{job['result']['dataset_id']}/data")[2]
        self.assertEqual(len(set(data["q"][0])), 1)
        self.assertGreater(len(set(data["q"][5])), 100)

        # A robot in use is not deleted; once its job ended it is.
        job = self.post("/v1/excitations", {"robot_id": ur5["id"], "max_seconds": 30})
        status, _, problem = self.server.request("DELETE", f"/v1/robots/{ur5['id']}")
        running = self.server.request("GET", f"/v1/jobs/{job['id']}")[2]["state"] in ("queued", "running")
        if running:
            self.assertEqual(status, 409, problem)
            self.assertEqual(problem["code"], "CONFLICT")
        self.server.request("POST", f"/v1/jobs/{job['id']}/cancel")  # its end is what matters, not its design
        self.server.wait_job(job["id"])
        status, _, _ = self.server.request("DELETE", f"/v1/robots/{ur5['id']}")
        self.assertIn(status, (204, 404) if not running else (204,))
        status, _, _ = self.server.request("GET", f"/v1/robots/{ur5['id']}")
        self.assertEqual(status, 404)
        self.assertEqual(self.server.request("GET", "/healthz")[0], 200)


if __name__ == "__main__":
    unittest.main()
