#!/usr/bin/env python3
"""embed_openapi.py — turns api/openapi.yaml into a C++ source file that returns the same
document as JSON text, so `manipid serve` answers GET /openapi.json from its own binary.

Usage: embed_openapi.py openapi.yaml output.cpp
Fails (non-zero) when the YAML does not parse or lacks the OpenAPI top-level keys.
"""
import json
import sys

import yaml


def main() -> int:
    source, target = sys.argv[1], sys.argv[2]
    with open(source, encoding="utf-8") as stream:
        document = yaml.safe_load(stream)
    for key in ("openapi", "info", "paths"):
        if key not in document:
            print(f"{source}: missing top-level key '{key}'", file=sys.stderr)
            return 1
    text = json.dumps(document, separators=(",", ":"), ensure_ascii=True)
    delimiter = "openapi"
    assert f"){delimiter}\"" not in text
    with open(target, "w", encoding="utf-8") as stream:
        stream.write("// Generated from api/openapi.yaml by api/tools/embed_openapi.py; do not edit.\n")
        stream.write('#include "manipid/api/routes.h"\n\n')
        stream.write("namespace manipid::api {\n")
        stream.write(f'const char* openapi_json() {{ return R"{delimiter}({text}){delimiter}"; }}\n')
        stream.write("}  // namespace manipid::api\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
