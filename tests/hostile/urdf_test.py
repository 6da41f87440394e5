"""urdf_test.py — hostile-client suite: URDF documents shaped to hurt the XML parser, against the real
`manipid serve` on port 0.

Items 1, 7 and 8 of hardening round 3: a 2-joint URDF with an element nested 40,000 deep (280 KB) crashed the
process (the XML parser recursed per level on the HTTP thread: SIGSEGV); 100,000 attributes on one
element took 44–56 s (a pairwise check) while every other robot request waited. Both are refused with
422 naming the document before the parser sees them, at once, and the server goes on answering. Numbers no link has (a mass of
1e-300 kg, negative damping) are refused at upload; an axis whose norm overflows is normalised.

Run: MANIPID_BIN=build/release/server/manipid python3 tests/hostile/urdf_test.py -v
"""
import os
import sys
import threading
import time
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "service"))
from harness import SharedServerTestCase  # noqa: E402

TWO_JOINTS = """<robot name="two">
  <link name="base"/>
  {extra}
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


def urdf(extra=""):
    return TWO_JOINTS.format(extra=extra).encode()


class HostileUrdf(SharedServerTestCase):
    def upload(self, document):
        return self.server.request("POST", "/v1/robots", document, {"Content-Type": "application/xml"})

    def assert_refused_quickly(self, document, words):
        started = time.monotonic()
        status, _, problem = self.upload(document)
        elapsed = time.monotonic() - started
        self.assertEqual(status, 422, problem)
        self.assertEqual(problem["field"], "urdf")
        for word in words:
            self.assertIn(word, problem["detail"])
        self.assertLess(elapsed, 5.0)  # a bound far above the milliseconds it takes, not a timing figure
        self.assertEqual(self.server.request("GET", "/healthz")[0], 200)
        self.assertIsNone(self.server.process.poll(), "the server died")

    def test_an_element_nested_40000_deep_is_refused_not_a_crash(self):
        deep = "<x>" * 40000 + "</x>" * 40000
        self.assert_refused_quickly(urdf(deep), ["nested 101 deep", "<x>"])
        # The robot list is untouched and a sound URDF is still accepted.
        status, _, robot = self.upload(urdf())
        self.assertEqual(status, 201, robot)
        self.assertEqual(len(robot["joints"]), 2)

    def test_100000_attributes_on_one_element_are_refused_at_once(self):
        wide = "<x " + " ".join(f'a{i}="1"' for i in range(100000)) + "/>"
        # While it is refused, another client's upload is not kept waiting behind it.
        answers = {}

        def other():
            answers["other"] = self.upload(urdf())[0]

        thread = threading.Thread(target=other)
        thread.start()
        self.assert_refused_quickly(urdf(wide), ["more than 100 attributes"])
        thread.join(30)
        self.assertEqual(answers.get("other"), 201)

    def test_absurd_numbers_are_refused_at_upload_not_fitted(self):
        # Item 7: masses of 1e-300 "succeeded" with physical and wrote inertias of 1e146; item 8: negative
        # damping was accepted at upload and refused only later.
        for document, element, words in [
                (urdf().replace(b'<mass value="1"/>', b'<mass value="1e-300"/>', 1), "l1", "mass of 1e-300 kg"),
                (urdf().replace(b'<axis xyz="0 0 1"/>', b'<axis xyz="0 0 1"/><dynamics damping="-1"/>', 1), "j1",
                 "negative <dynamics> damping")]:
            status, _, problem = self.upload(document)
            self.assertEqual(status, 422, problem)
            self.assertEqual(problem["field"], "urdf")
            self.assertIn(element, problem["detail"])
            self.assertIn(words, problem["detail"])
        # An axis of (1e200 1e200 0) overflowed to (0 0 0) and was accepted: now the direction it names.
        status, _, robot = self.upload(urdf().replace(b'<axis xyz="0 0 1"/>', b'<axis xyz="1e200 1e200 0"/>', 1))
        self.assertEqual(status, 201, robot)
        self.assertAlmostEqual(robot["joints"][0]["axis"][0], 0.5 ** 0.5, places=12)
        self.assertTrue(any("normalised" in warning for warning in robot["warnings"]), robot["warnings"])
        # An excitation whose acceleration limit leaves no motion "succeeded" with a condition number of ∞.
        status, _, problem = self.server.request("POST", "/v1/excitations",
                                                 {"robot_id": robot["id"], "max_acceleration": 1e-300})
        self.assertEqual(status, 422, problem)
        self.assertEqual(problem["field"], "max_acceleration")

    def test_a_chain_longer_than_any_manipulator_is_refused_at_once(self):
        # Item 4: a 100-joint upload computed its base parameters on the HTTP thread for 21 s and 367 MiB.
        links = ['<link name="l0"/>']
        for k in range(1, 101):
            links.append(f'<joint name="j{k}" type="revolute"><parent link="l{k - 1}"/><child link="l{k}"/>'
                         f'<origin xyz="0 0 0.1"/><axis xyz="0 {k % 2} {1 - k % 2}"/>'
                         '<limit lower="-2" upper="2" effort="50" velocity="2"/></joint>')
            links.append(f'<link name="l{k}"><inertial><mass value="1"/><origin xyz="0.01 0.02 0.05"/>'
                         '<inertia ixx="0.01" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.03"/></inertial></link>')
        document = ('<robot name="snake">' + "".join(links) + "</robot>").encode()
        self.assert_refused_quickly(document, ["100 moving joints", "at most 50", "base and tip"])

    def test_the_bound_leaves_room_for_real_documents(self):
        status, _, robot = self.upload(urdf("<x>" * 90 + "</x>" * 90))
        self.assertEqual(status, 201, robot)


if __name__ == "__main__":
    unittest.main()
