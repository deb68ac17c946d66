"""Test harness: routers on free ports, service processes that never outlive a test, waiting on the bus."""
