#!/bin/sh
# Fault injection (issue 25): checkpointed renders killed with SIGKILL at
# 108 seeded moments, each resumed to completion and compared with the
# uninterrupted image; prints the table BENCHMARKS.md quotes. Not part of
# the default test run (the test is --ignored: about a minute).
set -eu
cd "$(dirname "$0")/../.."
cargo test --release -p rtk-tests --test all killed_checkpointed_renders -- --ignored --nocapture 2>/dev/null | grep '^|'
