"""problem_details_test.py — hostile-client suite, part 3: what a problem's detail may say, and JSON
that nlohmann would take silently, against the real `manipid serve` on port 0.

Items 11 and 12 of the hardening issue: a key twice in one object is refused, naming it (nlohmann
keeps the last); details speak the user's language and stay short — no "[json.exception...]" for
1e400, no 300-digit numbers quoted back, a 414 that says 414 in its body too.

Run: MANIPID_BIN=build/debug/server/manipid python3 tests/hostile/problem_details_test.py -v
"""
import os
import sys
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "service"))
from harness import SharedServerTestCase  # noqa: E402

JSON = {"Content-Type": "application/json"}
DATASET = '"dt": 0.01, "q": [[0, 0.1, 0.2, 0.3]], "tau": [[1, 1, 1, 1]]'


class ProblemDetails(SharedServerTestCase):
    def problem(self, status, code, field, method, path, body=None, headers=None):
        answer_status, headers, problem = self.server.request(method, path, body, headers)
        self.assertEqual(answer_status, status, problem)
        self.assertEqual(headers["content-type"], "application/problem+json")
        self.assertEqual(problem["status"], status)
        self.assertEqual(problem["code"], code)
        self.assertEqual(problem.get("field"), field)
        self.assertNotIn("json.exception", problem["detail"])
        self.assertLess(len(problem["detail"]), 200, problem["detail"])
        return problem

    # ---- item 12: duplicate keys ----
    def test_a_key_twice_in_the_body_is_refused_naming_it(self):
        problem = self.problem(422, "INVALID_FIELD", "dt", "POST", "/v1/datasets", '{"dt": 0.01, ' + DATASET + "}", JSON)
        self.assertIn('the key "dt" appears twice in the body', problem["detail"])

    def test_a_key_twice_in_a_nested_object_is_refused_with_its_path(self):
        body = '{"simulation": {}, "initial": {"m1": 1.0, "m2": 1.0, "m1": 2.0}}'
        problem = self.problem(422, "INVALID_FIELD", "initial.m1", "POST", "/v1/identifications", body, JSON)
        self.assertIn('the key "m1" appears twice in initial', problem["detail"])
        body = '{"simulation": {"duration": 1, "noise": {"seed": 1, "seed": 2}}}'
        self.problem(422, "INVALID_FIELD", "simulation.noise.seed", "POST", "/v1/identifications", body, JSON)

    def test_a_key_twice_in_an_object_inside_arrays_is_refused_with_its_path(self):
        body = '{' + DATASET + ', "extra": [[1, 2], {"a": 1, "b": {"c": 1, "c": 2}}]}'
        self.problem(422, "INVALID_FIELD", "extra[1].b.c", "POST", "/v1/datasets", body, JSON)

    def test_the_same_key_in_sibling_objects_is_fine(self):
        # m1 in the simulated robot and in the starting values; not a duplicate. (Refused after
        # parsing for another reason, so no job runs: the parse itself let it through.)
        body = '{"simulation": {"parameters": {"m1": 1.0}, "noise": {"seed": 1}}, "initial": {"m1": 1.0}, "nope": 1}'
        status, _, problem = self.server.request("POST", "/v1/identifications", body, JSON)
        self.assertEqual((status, problem["field"]), (422, "nope"), problem)
        self.assertIn("unknown field", problem["detail"])

    # ---- item 11: details without internals ----
    def test_a_number_beyond_a_double_says_where_in_words(self):
        problem = self.problem(400, "MALFORMED_BODY", "body", "POST", "/v1/datasets",
                               '{"dt": 0.01, "q": [[0, 1e400, 0.2, 0.3]], "tau": [[1, 1, 1, 1]]}', JSON)
        self.assertIn("a number at q[0][1] is out of range", problem["detail"])
        problem = self.problem(400, "MALFORMED_BODY", "body", "POST", "/v1/identifications",
                               '{"simulation": {}, "initial": {"m2": -1e400}}', JSON)
        self.assertIn("at initial.m2", problem["detail"])

    def test_a_300_digit_number_is_never_quoted_whole(self):
        digits = "1" + "0" * 300
        problem = self.problem(400, "MALFORMED_BODY", "body", "POST", "/v1/datasets",
                               '{"dt": ' + digits + 'x, "q": [[0]]}', JSON)
        self.assertNotIn("0" * 25, problem["detail"])
        self.assertIn("parse error", problem["detail"])
        problem = self.problem(422, "INVALID_FIELD", "dt", "POST", "/v1/datasets",
                               '{"dt": ' + digits + ', "q": [[0, 0.1]], "tau": [[1, 1]]}', JSON)
        self.assertNotIn("0" * 25, problem["detail"])
        problem = self.problem(400, "MALFORMED_BODY", "body", "POST", "/v1/datasets", '{"dt": "' + "a" * 5000, JSON)
        self.assertNotIn("a" * 25, problem["detail"])

    def test_a_csv_number_out_of_range_is_quoted_short(self):
        digits = "1" + "0" * 400
        csv = f"t,q1,tau1\n0,0,1\n0.01,{digits},1\n0.02,0,1\n"
        problem = self.problem(422, "INVALID_FIELD", "q1", "POST", "/v1/datasets", csv, {"Content-Type": "text/csv"})
        self.assertNotIn("0" * 25, problem["detail"])

    def test_a_414_says_414_in_its_body_too(self):
        problem = self.problem(414, "URI_TOO_LONG", None, "GET", "/v1/jobs?page_token=" + "a" * 10000)
        self.assertIn("too long", problem["title"])
        self.assertEqual(self.server.request("GET", "/healthz")[0], 200)


if __name__ == "__main__":
    unittest.main()
