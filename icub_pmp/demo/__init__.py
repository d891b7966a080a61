"""The end-to-end demo: the papers' scenario on the simulated iCub, recorded and reported."""
