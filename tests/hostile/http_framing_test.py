"""http_framing_test.py — hostile-client suite, part 2: request smuggling and bodies read for nothing,
over raw sockets against the real `manipid serve` on port 0.

Items 3 and 4 of the hardening issue: a request refused before its body is read (401, 411, 413,
415, 400) must close the connection, so that the unread body is never read as the next request;
two Content-Lengths, Content-Length beside Transfer-Encoding, a length that is not a number and
a body on a GET are 400 and close; a Content-Length above --max-body is answered 413 from the
headers, without waiting for (or reading) the body, and the connection closed.

Run: MANIPID_BIN=build/debug/server/manipid python3 tests/hostile/http_framing_test.py -v
"""
import json
import os
import socket
import sys
import time
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "service"))
from harness import Server, temporary_directory  # noqa: E402

# What a smuggler hides in a body the server refuses without reading: if the server reads it as
# the next request on the connection, the answer is the job list.
SMUGGLED = b"GET /v1/jobs HTTP/1.1\r\nHost: x\r\n\r\n"
TOKEN = "s3cret-token"


class Connection:
    """One raw TCP connection; reads answers by their Content-Length (the server never chunks errors)."""

    def __init__(self, server, timeout=10):
        self.socket = socket.create_connection((server.host, server.port), timeout=timeout)
        self.buffer = b""

    def close(self):
        self.socket.close()

    def send(self, data):
        self.socket.sendall(data)

    def answer(self):
        """(status, headers with lower-case names, body) of the next answer; AssertionError at EOF."""
        while b"\r\n\r\n" not in self.buffer:
            chunk = self.socket.recv(65536)
            if not chunk:
                raise AssertionError(f"connection closed before an answer; got {self.buffer!r}")
            self.buffer += chunk
        head, self.buffer = self.buffer.split(b"\r\n\r\n", 1)
        lines = head.decode().split("\r\n")
        status = int(lines[0].split()[1])
        headers = {}
        for line in lines[1:]:
            name, value = line.split(":", 1)
            headers.setdefault(name.strip().lower(), []).append(value.strip())
        length = int(headers.get("content-length", ["0"])[0])
        while len(self.buffer) < length:
            chunk = self.socket.recv(65536)
            if not chunk:
                break
            self.buffer += chunk
        body, self.buffer = self.buffer[:length], self.buffer[length:]
        return status, headers, body

    def rest_until_closed(self, timeout=5.0):
        """Everything the server still sends until it closes; AssertionError if it stays open."""
        self.socket.settimeout(timeout)
        rest = self.buffer
        try:
            while True:
                chunk = self.socket.recv(65536)
                if not chunk:
                    return rest
                rest += chunk
        except ConnectionResetError:
            return rest
        except socket.timeout:
            raise AssertionError(f"the server kept the connection open {timeout} s; sent {rest!r}")


def post_head(path, length, *extra):
    lines = [f"POST {path} HTTP/1.1", "Host: x", "Content-Type: application/json", f"Content-Length: {length}", *extra]
    return ("\r\n".join(lines) + "\r\n\r\n").encode()


class Refusals(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.directory = temporary_directory()
        cls.server = Server(os.path.join(cls.directory.name, "jobs.db"), "--max-body", "4k").start()
        cls.guarded = Server(os.path.join(cls.directory.name, "guarded.db"), "--token", TOKEN).start()

    @classmethod
    def tearDownClass(cls):
        cls.server.stop()
        cls.guarded.stop()
        cls.directory.cleanup()

    def assert_refused_and_closed(self, server, head, body, status, code, field):
        """The refusal comes with "Connection: close", nothing answers the body, and the
        connection ends: sent at once, and with the body sent only after the refusal."""
        for body_after_answer in (False, True):
            with self.subTest(body_after_answer=body_after_answer):
                connection = Connection(server)
                try:
                    connection.send(head if body_after_answer else head + body)
                    answer_status, headers, answer_body = connection.answer()
                    self.assertEqual(answer_status, status, answer_body)
                    self.assertEqual(headers["content-type"], ["application/problem+json"])
                    self.assertEqual(headers.get("connection"), ["close"], headers)
                    self.assertNotIn("keep-alive", headers)
                    problem = json.loads(answer_body)
                    self.assertEqual(problem["status"], status)
                    self.assertEqual(problem["code"], code)
                    self.assertEqual(problem.get("field"), field)
                    if body_after_answer:
                        try:
                            connection.send(body)
                        except (BrokenPipeError, ConnectionResetError):
                            pass  # closed already: as good
                    rest = connection.rest_until_closed()
                    self.assertNotIn(b"HTTP/1.1", rest)  # the smuggled request was never answered
                finally:
                    connection.close()
        self.assertEqual(server.request("GET", "/healthz")[0], 200)

    def test_a_compressed_body_refused_with_415_is_not_read_as_the_next_request(self):
        head = post_head("/v1/datasets", len(SMUGGLED), "Content-Encoding: gzip")
        self.assert_refused_and_closed(self.server, head, SMUGGLED, 415, "UNSUPPORTED_MEDIA", "Content-Encoding")

    def test_a_chunked_body_refused_with_411_is_not_read(self):
        head = b"POST /v1/datasets HTTP/1.1\r\nHost: x\r\nContent-Type: text/csv\r\nTransfer-Encoding: chunked\r\n\r\n"
        body = b"%x\r\n%s\r\n0\r\n\r\n" % (len(SMUGGLED), SMUGGLED) + SMUGGLED
        self.assert_refused_and_closed(self.server, head, body, 411, "LENGTH_REQUIRED", "Transfer-Encoding")

    def test_a_body_refused_with_401_is_not_read(self):
        body = SMUGGLED.replace(b"Host: x\r\n", f"Host: x\r\nAuthorization: Bearer {TOKEN}\r\n".encode())
        head = post_head("/v1/datasets", len(body))
        self.assert_refused_and_closed(self.guarded, head, body, 401, "UNAUTHORIZED", "Authorization")

    def test_a_body_over_max_body_refused_with_413_is_not_read(self):
        body = b"x" * (5 * 1024 - len(SMUGGLED)) + SMUGGLED
        self.assert_refused_and_closed(self.server, post_head("/v1/datasets", len(body)), body, 413,
                                       "PAYLOAD_TOO_LARGE", "body")

    def test_a_client_that_sends_a_too_large_body_before_reading_still_gets_its_413(self):
        # Python's http.client (and curl below 1 MiB) send the whole body first: the refused
        # body is drained, not answered with a reset.
        for size in (64 * 1024, 8 * 1024 * 1024):
            with self.subTest(size=size):
                status, headers, problem = self.server.request("POST", "/v1/datasets", b"1" * size,
                                                               {"Content-Type": "text/csv"})
                self.assertEqual(status, 413, problem)
                self.assertEqual(problem["code"], "PAYLOAD_TOO_LARGE")

    def test_two_content_lengths_equal_or_not_are_400_and_close(self):
        for lengths in ((len(SMUGGLED), len(SMUGGLED)), (0, len(SMUGGLED)), (len(SMUGGLED), 0)):
            with self.subTest(lengths=lengths):
                head = post_head("/v1/datasets", lengths[0], f"Content-Length: {lengths[1]}")
                self.assert_refused_and_closed(self.server, head, SMUGGLED, 400, "MALFORMED_BODY", "Content-Length")

    def test_content_length_beside_transfer_encoding_is_400_and_close(self):
        body = b"%x\r\n%s\r\n0\r\n\r\n" % (len(SMUGGLED), SMUGGLED)
        head = post_head("/v1/datasets", len(SMUGGLED), "Transfer-Encoding: chunked")
        self.assert_refused_and_closed(self.server, head, body, 400, "MALFORMED_BODY", "Transfer-Encoding")

    def test_a_content_length_that_is_not_a_number_is_400_and_close(self):
        for value in ("abc", "-1", "+5", "5, 5", "0x10", "1e3"):
            with self.subTest(value=value):
                head = post_head("/v1/datasets", value)
                self.assert_refused_and_closed(self.server, head, SMUGGLED, 400, "MALFORMED_BODY", "Content-Length")
        # An empty value: cpp-httplib drops the header, so it is a body without a length.
        self.assert_refused_and_closed(self.server, post_head("/v1/datasets", ""), SMUGGLED, 411, "LENGTH_REQUIRED",
                                       "Content-Length")

    def test_a_body_on_a_get_or_delete_is_400_and_close(self):
        # cpp-httplib 0.11.4 never reads the body of a GET: it would be the next request. It
        # reads a DELETE's, but no route takes one.
        for method in ("GET", "DELETE"):
            with self.subTest(method=method):
                head = f"{method} /v1/jobs HTTP/1.1\r\nHost: x\r\nContent-Length: {len(SMUGGLED)}\r\n\r\n".encode()
                self.assert_refused_and_closed(self.server, head, SMUGGLED, 400, "MALFORMED_BODY", "body")

    def test_a_request_line_httplib_cannot_read_closes_the_connection(self):
        connection = Connection(self.server)
        try:
            connection.send(b"NOT A REQUEST\r\n\r\n" + SMUGGLED)
            status, headers, body = connection.answer()
            self.assertEqual(status, 400, body)
            self.assertEqual(json.loads(body)["status"], 400)
            self.assertNotIn(b"HTTP/1.1", connection.rest_until_closed())
        finally:
            connection.close()

    def test_keep_alive_still_works_for_good_requests(self):
        connection = Connection(self.server)
        try:
            for _ in range(3):
                connection.send(b"GET /healthz HTTP/1.1\r\nHost: x\r\n\r\n")
                status, headers, _ = connection.answer()
                self.assertEqual(status, 200)
                self.assertNotIn("close", headers.get("connection", []))
            body = b'{"dt": 0.01, "q": [[0, 0.1, 0.2]], "tau": [[1, 1, 1]]}'
            connection.send(post_head("/v1/datasets", len(body)) + body)
            status, _, answer = connection.answer()
            self.assertEqual(status, 201, answer)
            connection.send(b"GET /healthz HTTP/1.1\r\nHost: x\r\n\r\n")
            self.assertEqual(connection.answer()[0], 200)
        finally:
            connection.close()


class DeclaredTooLarge(unittest.TestCase):
    def test_10_gb_declared_is_answered_413_from_the_headers_and_closed(self):
        # Item 4: 0.11.4 read (and dropped) the whole declared body before answering: a client
        # that sends the headers and waits got no answer. 1 s is a generous bound, not a benchmark.
        with temporary_directory() as directory, Server(os.path.join(directory, "jobs.db")) as server:
            for path in ("/v1/datasets", "/v1/identifications", "/v1/no-such-route"):
                with self.subTest(path=path):
                    connection = Connection(server)
                    try:
                        started = time.monotonic()
                        connection.send(post_head(path, 10 * 1024 ** 3))
                        status, headers, body = connection.answer()
                        elapsed = time.monotonic() - started
                        self.assertEqual(status, 413, body)
                        self.assertLess(elapsed, 1.0)
                        problem = json.loads(body)
                        self.assertEqual(problem["code"], "PAYLOAD_TOO_LARGE")
                        self.assertEqual(problem["field"], "body")
                        self.assertIn("--max-body", problem["detail"])
                        self.assertIn("close", headers["connection"])
                        self.assertEqual(connection.rest_until_closed(timeout=3), b"")
                    finally:
                        connection.close()
            for length in ("99999999999999999999999999", str(2 ** 64), str(2 ** 64 + 1)):
                with self.subTest(length=length):  # beyond 64 bits: still 413, never wrapped to a small number
                    connection = Connection(server)
                    try:
                        connection.send(post_head("/v1/datasets", length))
                        self.assertEqual(connection.answer()[0], 413)
                        self.assertEqual(connection.rest_until_closed(timeout=3), b"")
                    finally:
                        connection.close()
            self.assertEqual(server.request("GET", "/healthz")[0], 200)

    def test_expect_100_continue_gets_413_instead_of_continue(self):
        # curl asks "Expect: 100-continue" before a body over 1 MiB; 0.11.4 said "100 Continue"
        # before any hook ran, so the client sent the whole body to be refused.
        with temporary_directory() as directory, Server(os.path.join(directory, "jobs.db"), "--max-body", "4k") as server:
            connection = Connection(server)
            try:
                connection.send(post_head("/v1/datasets", 10 * 1024 ** 3, "Expect: 100-continue"))
                status, headers, body = connection.answer()
                self.assertEqual(status, 413, body)
                self.assertEqual(json.loads(body)["code"], "PAYLOAD_TOO_LARGE")
                self.assertIn("close", headers["connection"])
                self.assertEqual(connection.rest_until_closed(timeout=3), b"")
            finally:
                connection.close()
            body = b'{"dt": 0.01, "q": [[0, 0.1, 0.2]], "tau": [[1, 1, 1]]}'
            connection = Connection(server)
            try:
                connection.send(post_head("/v1/datasets", len(body), "Expect: 100-continue"))
                self.assertEqual(connection.answer()[0], 100)
                connection.send(body)
                status, _, answer = connection.answer()
                self.assertEqual(status, 201, answer)
            finally:
                connection.close()


if __name__ == "__main__":
    unittest.main()
