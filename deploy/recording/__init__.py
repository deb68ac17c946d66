"""Recording, replaying and plotting runs (the ``ros2 bag`` role), with MCAP as the file format.

- :mod:`~deploy.recording.mcap_log` writes the file, :mod:`~deploy.recording.reading` reads it back;
- :mod:`~deploy.recording.recorder` takes samples off the bus, :mod:`~deploy.recording.sequence` counts losses
  from the publishers' sequence numbers, :mod:`~deploy.recording.summary` reports them;
- :mod:`~deploy.recording.replay` puts a recording back on the bus with its timing;
- :mod:`~deploy.recording.run_data` turns a recording into the data :mod:`deploy.plotting` draws.
"""
