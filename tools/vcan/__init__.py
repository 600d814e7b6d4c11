"""The firmware live on a SocketCAN bus: live_check (replay and record around navecu --can),
bus_run (the firmware stage of `make sim BUS=...`), vcan_selftest; docs/live-can.md."""
