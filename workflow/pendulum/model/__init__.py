"""Model: the rig and a model variant in, the simulated swing out: the equation of motion and its library of effects."""
