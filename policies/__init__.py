"""Policies: one interface (`policies.interface`), the privileged scripted baseline, ACT and Diffusion
Policy trained from the HDF5 episodes, the closed-loop runner that evaluates any of them."""
