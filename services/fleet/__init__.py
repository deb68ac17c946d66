"""The fleet service: who may charge at which dock, and in what order the others wait."""
