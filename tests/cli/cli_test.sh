#!/usr/bin/env bash
echo "cli tests: not yet written"; exit 0
