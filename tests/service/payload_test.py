"""payload_test.py — a payload on a URDF arm's tip link through the service alone, against the real binary on
port 0: a 6-joint arm that is not quite its URDF and a tool of known mass, centre of mass and inertia (a fixed
link on its flange), runs with measurement noise made by the real `manipid excitation` and `manipid torque`; the
arm identified from a run without the tool, then the payload from a run with it (arm_job_id); its views (fit,
validation, the URDF with the payload mounted); the URDF's values as the arm when none is named (another arm:
said); known values kept; a run without the payload (≈ 0 kg within its uncertainty, not an error); every bad
request refused with problem+json naming the field; an arm that has not finished refused; an arm deleted while
the payload job waited: the job fails naming arm_job_id, never lost.

Run: MANIPID_BIN=build/debug/server/manipid python3 tests/service/payload_test.py -v
"""
import json
import math
import os
import re
import subprocess
import sys
import unittest

sys.path.insert(0, os.path.dirname(__file__))
from harness import Server, binary, temporary_directory  # noqa: E402

SOURCE = os.path.join(os.path.dirname(__file__), "..", "..")
sys.path.insert(0, os.path.join(SOURCE, "clients", "python", "tests"))
from robot_data import with_tool  # noqa: E402  (the tool as a fixed link, as the clients' tests mount theirs)

UR5 = os.path.join(SOURCE, "examples", "robots", "ur5_like.urdf")

# The tool: 2 kg, its centre of mass off the flange's axis, an inertia about it with products (tool0's frame).
TOOL = {"mass": 2.0, "centre_of_mass": [0.03, -0.02, 0.08],
        "inertia": {"ixx": 0.006, "ixy": 0.0004, "ixz": -0.0003, "iyy": 0.007, "iyz": 0.0002, "izz": 0.004}}
MASS, COM, INERTIA = TOOL["mass"], TOOL["centre_of_mass"], TOOL["inertia"]
# A compact tool: a 2 kg sphere 1 cm in radius. Least squares on a noisy run gives it an inertia no body has.
SPHERE = {"mass": 2.0, "centre_of_mass": [0.0, 0.0, 0.05],
          "inertia": {"ixx": 8e-5, "ixy": 0.0, "ixz": 0.0, "iyy": 8e-5, "iyz": 0.0, "izz": 8e-5}}
# The arm as it is: off its URDF's values (link 3: 2.3 kg there), so only the arm as identified carries the tool right.
ARM_TRUTH = {"m3": 2.8, "fv2": 0.8, "fc2": 2.5}
NOISE = ["--noise-tau-relative", "0.01", "--noise-q", "2e-5", "--quantize-q", "18"]


def manipid(*arguments):
    done = subprocess.run([binary(), *arguments], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"manipid {' '.join(arguments)} failed: {done.stderr.strip()}")


class PayloadThroughTheService(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.directory = temporary_directory()
        cls.dir = cls.directory.name
        path = lambda name: os.path.join(cls.dir, name)  # noqa: E731
        with open(UR5) as stream:
            cls.document = stream.read()
        for name, tool in (("tool", TOOL), ("sphere", SPHERE)):
            with open(path(f"{name}.urdf"), "w") as stream:
                stream.write(with_tool(cls.document, "tool0", tool))
        # Two excitations of the bare arm; each run through the arm with or without the tool, noisy as a real log.
        for name, seed, period in (("a", 1, 10.0), ("b", 2, 8.0)):
            manipid("excitation", "--robot", UR5, "--period", repr(period), "--harmonics", "5", "--duration", repr(2 * period),
                    "--seed", str(seed), "--max-evaluations", "200", "--max-seconds", "120", "--out", path(f"excitation_{name}.csv"))
        # The arm is not quite its URDF: link 3 heavier, joint 2 with more friction.
        with open(path("truth.json"), "w") as stream:
            json.dump(ARM_TRUTH, stream)
        for run, urdf, excitation, seed in (("arm", UR5, "a", 11), ("tool", path("tool.urdf"), "b", 12),
                                            ("tool_check", path("tool.urdf"), "a", 13), ("bare", UR5, "b", 14),
                                            ("sphere", path("sphere.urdf"), "b", 15)):
            manipid("torque", "--robot", urdf, "--in", path(f"excitation_{excitation}.csv"), "--with-states", *NOISE,
                    "--params", path("truth.json"), "--seed", str(seed), "--out", path(f"{run}.csv"))
        cls.server = Server(path("jobs.db")).start()
        cls.robot = cls.post_ok("/v1/robots?name=ur5", cls.document, {"Content-Type": "application/xml"})
        cls.datasets = {}
        for run in ("arm", "tool", "tool_check", "bare", "sphere"):
            with open(path(f"{run}.csv")) as stream:
                cls.datasets[run] = cls.post_ok(f"/v1/datasets?name={run}", stream.read(), {"Content-Type": "text/csv"})["id"]
        cls.arm_job = cls.server.wait_job(cls.post_ok("/v1/identifications", {
            "robot_id": cls.robot["id"], "dataset_id": cls.datasets["arm"], "friction": ["viscous", "coulomb"]})["id"])
        assert cls.arm_job["state"] == "succeeded", cls.arm_job

    @classmethod
    def tearDownClass(cls):
        status = cls.server.stop()
        cls.directory.cleanup()
        assert status == 0, status

    @classmethod
    def post_ok(cls, path, body, headers=None):
        status, _, answer = cls.server.request("POST", path, body, headers)
        assert status in (200, 201, 202), (status, answer)
        return answer

    def payload(self, **fields):
        body = {"payload": True, "robot_id": self.robot["id"], "dataset_id": self.datasets["tool"], **fields}
        job = self.post_ok("/v1/identifications", body)
        self.assertEqual(job["kind"], "payload_identification", job)
        job = self.server.wait_job(job["id"])
        self.assertEqual(job["state"], "succeeded", job)
        return job

    def refused(self, body, field, words, status=422):
        answer_status, headers, problem = self.server.request("POST", "/v1/identifications", body)
        self.assertEqual(answer_status, status, (body, problem))
        self.assertTrue(headers["content-type"].startswith("application/problem+json"), headers)
        self.assertEqual(problem["field"], field, problem)
        self.assertIn(words, problem["detail"])
        return problem

    def check_tool(self, result, mass_tolerance, com_tolerance):
        self.assertTrue(result["detected"], result)
        self.assertLess(abs(result["mass"] - MASS), mass_tolerance, result)
        com_error = math.dist(result["centre_of_mass"], COM)
        self.assertLess(com_error, com_tolerance, result["centre_of_mass"])
        self.assertLess(result["fit"]["with_payload_error"], 0.5 * result["fit"]["arm_only_error"], result["fit"])

    def test_the_tool_on_the_identified_arm_with_its_views(self):
        job = self.payload(arm_job_id=self.arm_job["id"], validation_dataset_id=self.datasets["tool_check"])
        self.assertEqual(job["robot_id"], self.robot["id"])
        self.assertEqual(set(job["links"]) >= {"robot", "fit", "validation", "urdf"}, True, job["links"])
        self.assertNotIn("history", job["links"])
        result = job["result"]
        self.assertEqual(result["arm_job_id"], self.arm_job["id"])
        self.assertIn(self.arm_job["id"], result["arm"])
        self.assertEqual(result["robot"]["tip_link"], "tool0")
        # The arm identified from a 20 s noisy run without the tool (its error is the payload's): within 1 % and 2 mm.
        self.check_tool(result, 0.01 * MASS, 2e-3)
        # Its standard errors are numbers; the inertia about the centre of mass has all six entries.
        self.assertGreater(result["mass_std_error"], 0)
        self.assertEqual(sorted(result["inertia_about_com"]), sorted(INERTIA))
        self.assertEqual([p["name"] for p in result["parameters"]],
                         ["m", "mx", "my", "mz", "Ixx", "Ixy", "Ixz", "Iyy", "Iyz", "Izz"])
        # The held-out run is predicted better with the payload than without it.
        validation = result["validation"]
        self.assertLess(validation["with_payload"]["overall_relative_error"],
                        0.5 * validation["arm_only"]["overall_relative_error"], validation)
        for query, listed in ((f"kind=payload_identification&robot_id={self.robot['id']}", True),
                              ("kind=robot_identification", False)):
            status, _, page = self.server.request("GET", "/v1/jobs?" + query)
            self.assertEqual(status, 200, page)
            self.assertEqual(job["id"] in [item["id"] for item in page["items"]], listed, query)

        # /fit: per joint, the measured torque beside the arm's prediction with and without the payload.
        status, _, fit = self.server.request("GET", f"/v1/jobs/{job['id']}/fit?max_points=300")
        self.assertEqual(status, 200, fit)
        self.assertEqual(len(fit["joints"]), 6)
        for joint in fit["joints"]:
            self.assertEqual(len(joint["measured"]), len(fit["t"]))
            self.assertEqual(len(joint["arm_only"]), len(fit["t"]))
            self.assertLessEqual(len(fit["t"]), 301)
        self.assertLess(fit["overall_relative_error"], 0.5 * fit["arm_only"]["overall_relative_error"], fit["arm_only"])
        status, _, held_out = self.server.request("GET", f"/v1/jobs/{job['id']}/validation?max_points=300")
        self.assertEqual(status, 200, held_out)
        self.assertAlmostEqual(held_out["overall_relative_error"], validation["with_payload"]["overall_relative_error"], places=9)
        self.assertAlmostEqual(held_out["arm_only"]["overall_relative_error"],
                               validation["arm_only"]["overall_relative_error"], places=9)

        # /urdf: the robot's document with the payload as a fixed link on tool0, its mass the estimate's.
        status, headers, urdf = self.server.request("GET", f"/v1/jobs/{job['id']}/urdf")
        self.assertEqual(status, 200, urdf)
        self.assertIn("ur5-payload.urdf", headers["content-disposition"])
        self.assertIn('<link name="manipid_payload"', urdf)
        self.assertIn('<parent link="tool0"', urdf)
        mass = float(re.search(r'<link name="manipid_payload">.*?<mass value="([^"]+)"', urdf, re.S).group(1))
        self.assertAlmostEqual(mass, result["mass"], delta=1e-6 * MASS)
        self.assertIn(job["id"], urdf)

        # The views stand on the job's own result once the arm's job is gone.
        status, _, other = self.server.request("POST", "/v1/identifications", {
            "robot_id": self.robot["id"], "dataset_id": self.datasets["arm"], "friction": ["viscous", "coulomb"]})
        self.assertEqual(status, 202, other)
        other = self.server.wait_job(other["id"])
        copy = self.payload(arm_job_id=other["id"])
        self.assertEqual(self.server.request("DELETE", f"/v1/jobs/{other['id']}")[0], 204)
        self.assertEqual(self.server.request("GET", f"/v1/jobs/{copy['id']}/fit?max_points=50")[0], 200)
        self.assertEqual(self.server.request("GET", f"/v1/jobs/{copy['id']}/urdf")[0], 200)
        self.assertEqual(copy["result"]["mass"], result["mass"])  # the same arm, the same run: the same numbers

    def test_without_an_arm_the_urdfs_values_are_the_arm(self):
        # The runs' arm is not its URDF here: the payload on the URDF's values takes the arm's error for the tool's,
        # and a run without the tool on them is said to be another arm's, not passed off as a payload.
        result = self.payload()["result"]
        self.assertEqual(result["arm"], "the URDF's values")
        self.assertIsNone(result["arm_job_id"])
        urdf_values = self.robot["parameters"]["urdf_values"]
        self.assertEqual(sorted(result["arm_point"]), sorted(urdf_values))
        for name, value in urdf_values.items():
            self.assertAlmostEqual(result["arm_point"][name], value, delta=1e-12 * (1 + abs(value)), msg=name)
        self.assertGreater(abs(result["mass"] - MASS), 0.05 * MASS, result["mass"])
        other = self.payload(dataset_id=self.datasets["bare"])["result"]
        self.assertTrue(any("explains little" in warning for warning in other["warnings"]), other["warnings"])

    def test_physical_keeps_a_real_body_as_it_is(self):
        # The tool is a real body and the run determines it: the least-squares payload is one already, unchanged.
        plain = self.payload(arm_job_id=self.arm_job["id"])["result"]
        physical = self.payload(arm_job_id=self.arm_job["id"], physical=True)["result"]
        self.assertTrue(plain["consistent"], plain["consistency_findings"])
        self.assertIsNone(plain["physical"])
        self.assertIn("real rigid bodies", physical["method"])
        self.assertTrue(physical["consistent"])
        self.assertTrue(physical["physical"]["least_squares_consistent"], physical["physical"])
        self.assertEqual(physical["mass"], plain["mass"])
        self.refused({"payload": True, "robot_id": self.robot["id"], "dataset_id": self.datasets["tool"], "physical": 1},
                     "physical", "true or false")

    def test_physical_makes_a_compact_tool_a_real_body(self):
        # The sphere on the arm identified: least squares gives an inertia no body has, said; its URDF is refused
        # naming physical; asked for a real body, the answer is one, its mass and centre of mass kept.
        plain = self.payload(dataset_id=self.datasets["sphere"], arm_job_id=self.arm_job["id"])
        self.assertTrue(plain["result"]["detected"])
        self.assertFalse(plain["result"]["consistent"], plain["result"]["inertia_about_com"])
        self.assertTrue(any("positive definite" in finding for finding in plain["result"]["consistency_findings"]))
        status, _, problem = self.server.request("GET", f"/v1/jobs/{plain['id']}/urdf")
        self.assertEqual((status, problem["field"]), (409, "physical"), problem)
        self.assertIn('"physical": true', problem["detail"])
        physical = self.payload(dataset_id=self.datasets["sphere"], arm_job_id=self.arm_job["id"], physical=True)["result"]
        self.assertTrue(physical["consistent"], physical["consistency_findings"])
        self.assertFalse(physical["physical"]["least_squares_consistent"])
        self.assertGreater(physical["physical"]["relative_cost_increase"], 0)
        self.assertLess(abs(physical["mass"] - SPHERE["mass"]), 0.01 * SPHERE["mass"])
        self.assertLess(math.dist(physical["centre_of_mass"], SPHERE["centre_of_mass"]), 2e-3)

    def test_known_values_are_kept_and_the_options_passed_on(self):
        known = self.payload(arm_job_id=self.arm_job["id"], known_mass=MASS, known_centre_of_mass=COM,
                             torque_joints=[1, 2, 3, 4, 5, 6], judge_cutoff=4, judge_trim=0.2, comparison_cutoff=3,
                             trim=[0.1, 0.1])["result"]
        self.assertEqual(known["given"], {"mass": MASS, "centre_of_mass": COM})
        self.assertEqual(known["mass"], MASS)
        self.assertEqual(known["centre_of_mass"], COM)
        self.assertEqual(known["judge"]["cutoff_hz"], 4)
        self.assertEqual(known["judge"]["trim_seconds"], 0.2)
        self.assertEqual(known["filters"]["comparison_cutoff_hz"], 3)
        self.assertEqual(len(known["torque_joints"]), 6)
        # The inertia alone is estimated: near the tool's.
        for entry in ("ixx", "iyy", "izz"):
            self.assertLess(abs(known["inertia_about_com"][entry] - INERTIA[entry]), 4 * known["inertia_std_errors"][entry] + 5e-4,
                            (entry, known["inertia_about_com"], known["inertia_std_errors"]))

    def test_a_run_without_the_payload_answers_none_within_its_uncertainty(self):
        job = self.payload(dataset_id=self.datasets["bare"], arm_job_id=self.arm_job["id"])
        result = job["result"]
        self.assertFalse(result["detected"], result)
        self.assertLess(abs(result["mass"]), 3 * result["mass_std_error"], result)
        self.assertIsNone(result["centre_of_mass"][0])
        self.assertTrue(any("no payload" in warning for warning in result["warnings"]), result["warnings"])
        status, _, problem = self.server.request("GET", f"/v1/jobs/{job['id']}/urdf")
        self.assertEqual(status, 409, problem)
        self.assertIn("no payload", problem["detail"])

    def test_bad_requests_name_their_field(self):
        robot, arm, tool = self.robot["id"], self.arm_job["id"], self.datasets["tool"]
        base = {"payload": True, "robot_id": robot, "dataset_id": tool}
        self.refused({"payload": True, "dataset_id": tool}, "robot_id", "missing robot_id")
        self.refused({**base, "payload": False}, "payload", "payload must be true")
        self.refused({**base, "payload": "yes"}, "payload", "payload must be true")
        self.refused({"payload": True, "robot_id": robot}, "dataset_id", "missing dataset_id")
        self.refused({**base, "robot_id": "rb_0000000000000000"}, "robot_id", "rb_0000000000000000")
        self.refused({**base, "known_mass": 0}, "known_mass", "known_mass")
        self.refused({**base, "known_mass": -2}, "known_mass", "known_mass")
        self.refused({**base, "known_centre_of_mass": [0, 0]}, "known_centre_of_mass", "[x, y, z]")
        self.refused({**base, "known_centre_of_mass": [0, "a", 0]}, "known_centre_of_mass[1]", "number")
        self.refused({**base, "torque_joints": [7]}, "torque_joints", "has 6")
        self.refused({**base, "comparison_cutoff": "auto"}, "comparison_cutoff", "comparison_cutoff")
        self.refused({**base, "friction": ["viscous"]}, "friction", "arm_job_id")
        self.refused({**base, "method": "two-stage"}, "method", "paper's preset")
        self.refused({**base, "dataset_id": "ds_0000000000000000"}, "dataset_id", "no dataset")
        self.refused({**base, "validation_dataset_id": "ds_0000000000000000"}, "validation_dataset_id", "no dataset")
        self.refused({**base, "known_mas": 1}, "known_mas", "did you mean \"known_mass\"")
        four = self.post_ok("/v1/datasets", {"dt": 0.001, "q": [[0.0] * 50] * 4, "tau": [[0.0] * 50] * 4})["id"]
        self.refused({**base, "dataset_id": four}, "dataset_id", "4 joints, the robot ur5_like has 6")
        # The arm: a job that is there, a robot identification, of this robot, succeeded.
        self.refused({**base, "arm_job_id": "job_0000000000000000"}, "arm_job_id", "no job job_0000000000000000")
        simulation = self.server.wait_job(self.post_ok("/v1/simulations", {"duration": 0.2})["id"])
        self.refused({**base, "arm_job_id": simulation["id"]}, "arm_job_id", "not a robot_identification")
        other = self.post_ok("/v1/robots?name=other", self.document, {"Content-Type": "application/xml"})
        self.refused({**base, "robot_id": other["id"], "arm_job_id": arm}, "arm_job_id", f"identified robot {robot}, not")
        # Nothing was queued by any of these.
        status, _, page = self.server.request("GET", "/v1/jobs?kind=payload_identification&page_size=1000")
        queued = [item for item in page["items"] if item["state"] in ("queued", "running")]
        self.assertEqual(queued, [])

    def test_an_arm_that_has_not_finished_is_refused(self):
        # A server without workers: the arm's identification stays queued.
        directory = temporary_directory()
        try:
            with Server(os.path.join(directory.name, "jobs.db"), workers=0) as server:
                status, _, robot = server.request("POST", "/v1/robots", self.document, {"Content-Type": "application/xml"})
                self.assertEqual(status, 201, robot)
                with open(os.path.join(self.dir, "tool.csv")) as stream:
                    status, _, dataset = server.request("POST", "/v1/datasets", stream.read(), {"Content-Type": "text/csv"})
                self.assertEqual(status, 201, dataset)
                status, _, arm = server.request("POST", "/v1/identifications", {"robot_id": robot["id"], "dataset_id": dataset["id"]})
                self.assertEqual(status, 202, arm)
                body = {"payload": True, "robot_id": robot["id"], "dataset_id": dataset["id"], "arm_job_id": arm["id"]}
                status, _, problem = server.request("POST", "/v1/identifications", body)
                self.assertEqual((status, problem["field"]), (422, "arm_job_id"), problem)
                self.assertIn("is queued: submit the payload identification once it has succeeded", problem["detail"])
                self.assertEqual(server.request("POST", f"/v1/jobs/{arm['id']}/cancel")[0], 200)
                status, _, problem = server.request("POST", "/v1/identifications", body)
                self.assertEqual((status, problem["field"]), (422, "arm_job_id"), problem)
                self.assertIn("was cancelled", problem["detail"])
                # Without an arm the URDF's values are the arm: queued (and cancelled: no worker here).
                del body["arm_job_id"]
                status, _, job = server.request("POST", "/v1/identifications", body)
                self.assertEqual(status, 202, job)
                self.assertEqual(job["kind"], "payload_identification")
                self.assertEqual(server.request("POST", f"/v1/jobs/{job['id']}/cancel")[0], 200)
        finally:
            directory.cleanup()

    def test_an_arm_deleted_before_the_job_ran_fails_it_naming_arm_job_id(self):
        # One database, three processes: the arm identified; the payload queued (no workers) and its arm deleted;
        # then a worker runs it: failed, saying what was deleted, never lost.
        directory = temporary_directory()
        try:
            db = os.path.join(directory.name, "jobs.db")
            with Server(db) as server:
                robot = server.request("POST", "/v1/robots", self.document, {"Content-Type": "application/xml"})[2]
                ids = {}
                for run in ("arm", "tool"):
                    with open(os.path.join(self.dir, f"{run}.csv")) as stream:
                        ids[run] = server.request("POST", "/v1/datasets", stream.read(), {"Content-Type": "text/csv"})[2]["id"]
                arm = server.wait_job(server.request("POST", "/v1/identifications", {
                    "robot_id": robot["id"], "dataset_id": ids["arm"], "friction": ["viscous", "coulomb"]})[2]["id"])
                self.assertEqual(arm["state"], "succeeded", arm)
            with Server(db, workers=0) as server:
                status, _, job = server.request("POST", "/v1/identifications", {
                    "payload": True, "robot_id": robot["id"], "dataset_id": ids["tool"], "arm_job_id": arm["id"]})
                self.assertEqual(status, 202, job)
                self.assertEqual(server.request("DELETE", f"/v1/jobs/{arm['id']}")[0], 204)
            with Server(db) as server:
                job = server.wait_job(job["id"])
                self.assertEqual(job["state"], "failed", job)
                self.assertEqual(job["error"]["field"], "arm_job_id", job["error"])
                self.assertIn(f"job {arm['id']} was deleted before the job ran", job["error"]["detail"])
        finally:
            directory.cleanup()


if __name__ == "__main__":
    unittest.main()
