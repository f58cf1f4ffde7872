"""Seeded fuzzers over naoloc's real servers on loopback (used by tests/test_fuzz_*.py)."""
