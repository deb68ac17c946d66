"""The live view: a bridge from zendock's topics to the Foxglove WebSocket protocol (Foxglove, Lichtblick)."""
