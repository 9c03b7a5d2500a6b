"""The hardware side, without Qt and without the workbench: the CS-2000 driver and emulator, the simulated headset, and the patch displays."""
