"""Applications (layer 8): a run as a pure function of its configuration, the CLI, batches."""
