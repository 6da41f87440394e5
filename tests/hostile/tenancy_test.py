"""tenancy_test.py — hostile-client suite: one lab server shared by groups, each with its own named
token (`manipid serve --token-file`), against the real `manipid serve` on port 0.

Issue 29 item 9: one shared token let every holder list, cancel and delete everyone's jobs, datasets
and robots. With named tokens each dataset, robot and job is its creator's name's: a second client
sees none of the first one's resources, and what is not its own answers exactly as what does not
exist (404, or 422 naming the field a request names it in; never 403). An admin token sees all. A
token file that is wrong in any way stops the server at start-up, naming the line, never the token.

Run: MANIPID_BIN=build/release/server/manipid python3 tests/hostile/tenancy_test.py -v
"""
import os
import subprocess
import sys
import time
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "service"))
from harness import Server, binary, temporary_directory  # noqa: E402

ALICE = "alice-3f9c2b7d41e8a605"
BOB = "bob-8d1e6a4c0b92f735ee"
CAROL = "carol-5b0a7e91c2d84f36"  # the admin

TOKEN_FILE = f"""# who may use this server
alice  {ALICE}
bob:{BOB}

admin carol {CAROL}
"""

TWO_JOINTS = b"""<robot name="two">
  <link name="base"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="10" velocity="2"/></joint>
  <link name="l1"><inertial><mass value="1"/><origin xyz="0.1 0 0"/>
    <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0.3 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-3" upper="3" effort="10" velocity="2"/></joint>
  <link name="l2"><inertial><mass value="1"/><origin xyz="0.1 0 0"/>
    <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
</robot>
"""

# A small measured run of a 4-joint arm (the paper's preset): 50 samples at 1 ms, with torque.
RUN = {"dt": 0.001, "q": [[0.01 * i * (j + 1) for i in range(50)] for j in range(4)],
       "tau": [[0.1 * (j + 1) + 0.001 * i for i in range(50)] for j in range(4)]}


def bearer(token):
    return {"Authorization": f"Bearer {token}"}


def write_token_file(directory, text, mode=0o600, name="tokens"):
    path = os.path.join(directory, name)
    with open(path, "w") as stream:
        stream.write(text)
    os.chmod(path, mode)
    return path


class TwoGroupsOneServer(unittest.TestCase):
    """Alice's resources, made once; bob and the admin look at them. The server runs no jobs
    (--workers 0): alice's job stays queued, so a cancel that reached it would show."""

    @classmethod
    def setUpClass(cls):
        cls.directory = temporary_directory()
        cls.tokens = write_token_file(cls.directory.name, TOKEN_FILE)
        cls.db = os.path.join(cls.directory.name, "jobs.db")
        cls.server = Server(cls.db, "--token-file", cls.tokens, workers=0).start()
        cls.dataset = cls.call("POST", "/v1/datasets", ALICE, {"name": "alice's run", **RUN}, expect=201)
        cls.robot = cls.call("POST", "/v1/robots?name=alices-arm", ALICE, TWO_JOINTS, expect=201,
                             headers={"Content-Type": "application/xml"})
        cls.job = cls.call("POST", "/v1/identifications", ALICE, {"dataset_id": cls.dataset["id"], "preset": "cedro2009"},
                           expect=202, headers={"Idempotency-Key": "run-42"})

    @classmethod
    def tearDownClass(cls):
        cls.server.stop()
        cls.directory.cleanup()

    @classmethod
    def call(cls, method, path, token, body=None, expect=None, headers=None):
        status, _, answer = cls.server.request(method, path, body, {**(bearer(token) if token else {}), **(headers or {})})
        if expect is not None:
            assert status == expect, (method, path, status, answer)
        return answer

    def request(self, method, path, token, body=None, headers=None):
        return self.server.request(method, path, body, {**(bearer(token) if token else {}), **(headers or {})})

    def assert_missing(self, method, path, token, body=None, field="id"):
        """As a resource that does not exist: the same status, code, title and field."""
        status, _, problem = self.request(method, path, token, body)
        self.assertEqual(status, 404, problem)
        self.assertEqual((problem["code"], problem["field"]), ("NOT_FOUND", field))
        made_up = path.replace(self.job["id"], "job_0000000000000000").replace(self.dataset["id"], "ds_0000000000000000")
        made_up = made_up.replace(self.robot["id"], "rb_0000000000000000")
        status_missing, _, missing = self.request(method, made_up, token, body)
        self.assertEqual(status_missing, 404)
        self.assertEqual({k: v for k, v in problem.items() if k not in ("detail", "instance")},
                         {k: v for k, v in missing.items() if k not in ("detail", "instance")})
        return problem

    def alices_job(self):
        return self.call("GET", f"/v1/jobs/{self.job['id']}", ALICE, expect=200)

    def test_alice_owns_what_she_made(self):
        self.assertEqual(self.dataset["owner"], "alice")
        self.assertEqual(self.robot["owner"], "alice")
        self.assertEqual(self.job["owner"], "alice")
        jobs = self.call("GET", "/v1/jobs", ALICE, expect=200)["items"]
        self.assertIn(self.job["id"], [job["id"] for job in jobs])
        self.assertEqual({job["owner"] for job in jobs}, {"alice"})

    def test_bob_lists_none_of_alices_resources(self):
        alices = {self.job["id"], self.dataset["id"], self.robot["id"]}
        for path in ("/v1/jobs", "/v1/datasets", "/v1/robots", "/v1/jobs?state=queued",
                     f"/v1/jobs?robot_id={self.robot['id']}", "/v1/jobs?kind=identification",
                     "/v1/jobs?kind=robot_identification"):
            items = self.call("GET", path, BOB, expect=200)["items"]
            self.assertFalse(alices & {item["id"] for item in items}, path)
            self.assertTrue(all(item["owner"] == "bob" for item in items), path)
        self.assertEqual(self.call("GET", f"/v1/jobs?robot_id={self.robot['id']}", BOB, expect=200)["items"], [])

    def test_bob_cannot_see_cancel_or_delete_alices_job_and_it_is_untouched(self):
        before = self.alices_job()
        job = self.job["id"]
        for method, path in (("GET", f"/v1/jobs/{job}"), ("GET", f"/v1/jobs/{job}?wait=1"),
                             ("GET", f"/v1/jobs/{job}/history"), ("GET", f"/v1/jobs/{job}/history?max_points=10"),
                             ("GET", f"/v1/jobs/{job}/fit"), ("GET", f"/v1/jobs/{job}/validation"),
                             ("GET", f"/v1/jobs/{job}/urdf"), ("DELETE", f"/v1/jobs/{job}")):
            self.assert_missing(method, path, BOB)
        self.assert_missing("POST", f"/v1/jobs/{job}/cancel", BOB, body=b"")
        self.assert_missing("POST", f"/v1/jobs/{job}:cancel", BOB, body={})
        after = self.alices_job()
        self.assertEqual(after["state"], "queued")
        self.assertFalse(after["cancel_requested"])
        self.assertEqual(before, after)

    def test_bob_cannot_read_or_delete_alices_dataset_and_robot(self):
        ds, rb = self.dataset["id"], self.robot["id"]
        for method, path in (("GET", f"/v1/datasets/{ds}"), ("GET", f"/v1/datasets/{ds}?format=csv"),
                             ("GET", f"/v1/datasets/{ds}/data"), ("DELETE", f"/v1/datasets/{ds}"),
                             ("GET", f"/v1/robots/{rb}"), ("GET", f"/v1/robots/{rb}?format=urdf"),
                             ("DELETE", f"/v1/robots/{rb}")):
            self.assert_missing(method, path, BOB)
        self.assertEqual(self.call("GET", f"/v1/datasets/{ds}", ALICE, expect=200)["id"], ds)
        self.assertEqual(self.call("GET", f"/v1/robots/{rb}", ALICE, expect=200)["id"], rb)

    def test_bob_naming_alices_dataset_or_robot_is_refused_as_if_it_did_not_exist(self):
        cases = [("/v1/identifications", {"dataset_id": self.dataset["id"], "preset": "cedro2009"}, "dataset_id"),
                 ("/v1/excitations", {"robot_id": self.robot["id"]}, "robot_id"),
                 ("/v1/identifications", {"robot_id": self.robot["id"], "dataset_id": "ds_0000000000000000"}, "robot_id")]
        for path, body, field in cases:
            status, _, problem = self.request("POST", path, BOB, body)
            self.assertEqual((status, problem["code"], problem["field"]), (422, "INVALID_FIELD", field), problem)
            missing = {k: ("ds_0000000000000000" if v == self.dataset["id"] else
                           "rb_0000000000000000" if v == self.robot["id"] else v) for k, v in body.items()}
            status_missing, _, problem_missing = self.request("POST", path, BOB, missing)
            self.assertEqual(status_missing, status)
            self.assertEqual(problem["detail"].split()[:2], problem_missing["detail"].split()[:2])  # "no dataset …"
        # A dataset upload that names alice's robot for its joint names: the same.
        status, _, problem = self.request("POST", f"/v1/datasets?robot_id={self.robot['id']}", BOB,
                                          "t,q1,q2\n0,0,0\n0.001,0,0\n", {"Content-Type": "text/csv"})
        self.assertEqual((status, problem["field"]), (422, "robot_id"), problem)
        for job in self.call("GET", "/v1/jobs", BOB, expect=200)["items"]:  # nothing was queued on hers
            self.assertNotIn(job["dataset_id"], (self.dataset["id"],))
            self.assertNotEqual(job["robot_id"], self.robot["id"])

    def test_bobs_idempotency_key_is_his_own(self):
        body = {"dataset_id": self.dataset["id"], "preset": "cedro2009"}
        # The same key and body alice sent: bob never gets her job back (her dataset is not his either).
        status, headers, answer = self.request("POST", "/v1/identifications", BOB, body, {"Idempotency-Key": "run-42"})
        self.assertEqual(status, 422, answer)
        self.assertNotIn("idempotent-replayed", headers)
        self.assertNotIn(self.job["id"], str(answer))
        # A simulation under alice's key: a new job, bob's.
        status, headers, his = self.request("POST", "/v1/simulations", BOB, {"duration": 0.5}, {"Idempotency-Key": "run-42"})
        self.assertEqual(status, 202, his)
        self.assertNotIn("idempotent-replayed", headers)
        self.assertNotEqual(his["id"], self.job["id"])
        self.assertEqual(his["owner"], "bob")
        status, headers, again = self.request("POST", "/v1/simulations", BOB, {"duration": 0.5}, {"Idempotency-Key": "run-42"})
        self.assertEqual((status, again["id"], headers.get("idempotent-replayed")), (202, his["id"], "true"))
        # Alice's replay is still hers.
        status, headers, mine = self.request("POST", "/v1/identifications", ALICE, body, {"Idempotency-Key": "run-42"})
        self.assertEqual((status, mine["id"], headers.get("idempotent-replayed")), (202, self.job["id"], "true"))
        self.assertNotIn(his["id"], [job["id"] for job in self.call("GET", "/v1/jobs", ALICE, expect=200)["items"]])

    def test_the_admin_sees_and_may_act_on_everyones(self):
        listed = {job["id"]: job["owner"] for job in self.call("GET", "/v1/jobs", CAROL, expect=200)["items"]}
        self.assertEqual(listed.get(self.job["id"]), "alice")
        self.assertIn(self.dataset["id"], [d["id"] for d in self.call("GET", "/v1/datasets", CAROL, expect=200)["items"]])
        self.assertIn(self.robot["id"], [r["id"] for r in self.call("GET", "/v1/robots", CAROL, expect=200)["items"]])
        self.assertEqual(self.call("GET", f"/v1/jobs/{self.job['id']}", CAROL, expect=200)["owner"], "alice")
        # What the admin makes is the admin's own: alice does not see it.
        made = self.call("POST", "/v1/simulations", CAROL, {"duration": 0.5}, expect=202)
        self.assertEqual(made["owner"], "carol")
        self.assert_missing("GET", f"/v1/jobs/{made['id']}", ALICE)
        # /metrics counts every owner's jobs: the admin's alone.
        self.assertEqual(self.request("GET", "/metrics", CAROL)[0], 200)
        status, _, problem = self.request("GET", "/metrics", ALICE)
        self.assertEqual((status, problem["code"]), (403, "FORBIDDEN"))

    def test_a_bad_or_missing_token_is_401(self):
        for token in (None, "wrong-token-0123456789", ALICE[:-1], ALICE + "x", "carol"):
            status, headers, problem = self.request("GET", "/v1/jobs", token)
            self.assertEqual((status, problem["code"]), (401, "UNAUTHORIZED"), token)
            self.assertEqual(headers.get("www-authenticate"), "Bearer")
        self.assertEqual(self.request("GET", "/v1/jobs", None, headers={"Authorization": ALICE})[0], 401)
        self.assertEqual(self.request("GET", "/healthz", None)[0], 200)  # outside the tokens' reach, as before

    def test_pages_hold_ones_own_and_a_page_token_serves_no_other_list(self):
        mine = [self.dataset["id"]]
        for i in range(3):
            mine.append(self.call("POST", "/v1/datasets", ALICE, {"name": f"alice {i}", **RUN}, expect=201)["id"])
            self.call("POST", "/v1/datasets", BOB, {"name": f"bob {i}", **RUN}, expect=201)
        seen, token = [], ""
        while True:
            page = self.call("GET", "/v1/datasets?page_size=1" + (f"&page_token={token}" if token else ""), ALICE, expect=200)
            seen += [d["id"] for d in page["items"]]
            if "next_page_token" not in page:
                break
            token = page["next_page_token"]
            status, _, problem = self.request("GET", f"/v1/datasets?page_size=1&page_token={token}", BOB)
            self.assertEqual((status, problem["field"]), (422, "page_token"))
        self.assertEqual(len(seen), len(set(seen)))  # no page repeats one
        self.assertTrue(set(mine) <= set(seen))
        owners = {d["owner"] for d in self.call("GET", "/v1/datasets?page_size=1000", ALICE, expect=200)["items"]}
        self.assertEqual(owners, {"alice"})

    def test_the_log_names_the_owner_never_the_token(self):
        self.call("GET", "/v1/robots", BOB, expect=200)
        log = self.server.read_log()
        self.assertIn("GET /v1/robots 200", log)
        self.assertIn(" by bob\n", log)
        for token in (ALICE, BOB, CAROL):
            self.assertNotIn(token, log)


class AJobsOutputIsItsOwners(unittest.TestCase):
    def test_a_simulated_dataset_is_the_submitters_and_owners_survive_a_restart(self):
        with temporary_directory() as directory:
            tokens = write_token_file(directory, TOKEN_FILE)
            db = os.path.join(directory, "jobs.db")
            with Server(db, "--token-file", tokens, workers=1) as server:
                status, _, job = server.request("POST", "/v1/simulations", {"duration": 0.3}, bearer(ALICE))
                self.assertEqual(status, 202, job)
                deadline = time.time() + 300
                while job["state"] not in ("succeeded", "failed", "cancelled") and time.time() < deadline:
                    status, _, job = server.request("GET", f"/v1/jobs/{job['id']}?wait=10", headers=bearer(ALICE))
                self.assertEqual(job["state"], "succeeded", job)
                made = job["dataset_id"]
            with Server(db, "--token-file", tokens, workers=0) as server:
                status, _, dataset = server.request("GET", f"/v1/datasets/{made}", headers=bearer(ALICE))
                self.assertEqual((status, dataset["owner"]), (200, "alice"))
                self.assertEqual(server.request("GET", f"/v1/datasets/{made}", headers=bearer(BOB))[0], 404)
                self.assertEqual(server.request("GET", f"/v1/jobs/{job['id']}", headers=bearer(BOB))[0], 404)
                self.assertEqual(server.request("GET", "/v1/datasets", headers=bearer(BOB))[2]["items"], [])


class ATokenFileThatIsWrongStopsTheServer(unittest.TestCase):
    def refused(self, *arguments, text=None, mode=0o600, env=None):
        """Starts serve with the arguments (a token file of `text` first); its exit status and stderr."""
        with temporary_directory() as directory:
            command = [binary(), "serve", "--port", "0", "--workers", "0", "--db", os.path.join(directory, "jobs.db")]
            if text is not None:
                command += ["--token-file", write_token_file(directory, text, mode)]
            environment = {k: v for k, v in os.environ.items() if not k.startswith("MANIPID_TOKEN")}
            result = subprocess.run(command + list(arguments), capture_output=True, timeout=60, env={**environment, **(env or {})})
            self.assertFalse(result.stdout.startswith(b"listening"), result.stdout)
            self.assertFalse(os.path.exists(os.path.join(directory, "jobs.db")), "a refused server touched its database")
            return result.returncode, result.stderr.decode()

    def assert_refused(self, words, **kwargs):
        status, message = self.refused(**kwargs)
        self.assertNotEqual(status, 0, message)
        self.assertEqual(status, 2, message)  # a usage error, like any wrong option
        for word in words:
            self.assertIn(word, message)
        for token in (ALICE, BOB, CAROL, "short-token"):
            self.assertNotIn(token, message)  # never echoed
        return message

    def test_a_name_given_twice(self):
        self.assert_refused(["line 3", "alice", "twice", "line 1"], text=f"alice {ALICE}\nbob {BOB}\nalice {CAROL}\n")

    def test_a_token_given_twice(self):
        self.assert_refused(["line 2", "line 1", "token"], text=f"alice {ALICE}\nbob {ALICE}\n")

    def test_a_short_token(self):
        self.assert_refused(["line 2", "bob", "11 characters", "at least 16"], text=f"alice {ALICE}\nbob short-token\n")

    def test_a_line_that_is_none_of_the_forms(self):
        self.assert_refused(["line 3", "NAME TOKEN"], text=f"# tokens\nalice {ALICE}\nbob {BOB} extra\n")
        self.assert_refused(["line 1", "admin"], text=f"admin {ALICE}\n")  # "admin" marks; it is not a name
        self.assert_refused(["line 1", "name"], text=f"al/ice {ALICE}\n")
        self.assert_refused(["no tokens"], text="# nothing yet\n\n")

    def test_a_file_other_users_may_read(self):
        self.assert_refused(["mode 644", "chmod 600"], text=f"alice {ALICE}\n", mode=0o644)
        self.assert_refused(["mode 620", "chmod 600"], text=f"alice {ALICE}\n", mode=0o620)

    def test_a_missing_file_and_token_beside_it(self):
        self.assert_refused(["--token-file", "No such file"], text=None, env={"MANIPID_TOKEN_FILE": "/nonexistent/tokens"})
        self.assert_refused(["--token", "--token-file", "both"], text=f"alice {ALICE}\n", env={"MANIPID_TOKEN": "s3cret-token-0123"})

    def test_a_good_file_from_the_environment_starts(self):
        with temporary_directory() as directory:
            tokens = write_token_file(directory, TOKEN_FILE)
            previous = os.environ.get("MANIPID_TOKEN_FILE")
            os.environ["MANIPID_TOKEN_FILE"] = tokens
            try:
                with Server(os.path.join(directory, "jobs.db"), workers=0) as server:
                    self.assertEqual(server.request("GET", "/v1/jobs")[0], 401)
                    self.assertEqual(server.request("GET", "/v1/jobs", headers=bearer(BOB))[0], 200)
                    self.assertIn("3 named tokens required (1 admin)", server.read_log())
            finally:
                if previous is None:
                    del os.environ["MANIPID_TOKEN_FILE"]
                else:
                    os.environ["MANIPID_TOKEN_FILE"] = previous


if __name__ == "__main__":
    unittest.main()
