"""Training of the learned controllers (``ego train ...``)."""
