"""The Nomad 200 office task: geometry, sensors, the single and the batched environment."""
