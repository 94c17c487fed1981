"""The skillbus gripper's electronic data sheet (deploy/can/skillbus_gripper.eds): the
object dictionary that the driver, the simulated device and `can-log` share. A real
CiA 402 gripper comes with its own EDS; give that to the driver instead."""

from pathlib import Path

EDS = Path(__file__).resolve().parents[3] / "deploy" / "can" / "skillbus_gripper.eds"

# TPDO1's variables as the EDS maps them (skillbus.can.pdo_codec reads and writes them).
TPDO1_FIELDS = ("Statusword", "Position actual value", "Grip state")
