"""``skillbus generate``: demonstration episodes at scale (docs/generate.md). Randomized
scenes, a manipulation task run in lockstep faster than real time, each episode recorded
into a LeRobot dataset (v2.1 layout: one parquet file per episode) with its seed and
digests, in parallel worker processes or on a Ray cluster."""
