"""The model sections of a scene: what the machine is (``[gearbox]`` with its supports and the
bearing catalogue, ``[rotor]`` and its shaft meshing, ``[housing]`` with its bores, walls,
mesh and sizing) and the layout checks that join them."""
