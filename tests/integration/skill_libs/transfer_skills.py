"""A test library: the real TransferProducts compound over Pick and Place primitives that
only move containment in the world model, the first Place failing like a release cut
short by a gripper fault (the product stays in the gripper). Used by
test_transfer_retry.py."""

from skillbus.skill import PrimitiveBase
from skillbus.skills.manipulation import Pick, Place, TransferProducts, transfer_products
from skillbus.world.poses import reparent


class transfer_products_under_test(transfer_products):
    def createDescription(self):
        self.setDescription(TransferProducts(), "transfer_products")


class held_pick(PrimitiveBase):
    def createDescription(self):
        self.setDescription(Pick(), "held_pick")

    def execute(self):
        reparent(self.wmi, self.params["Object"].value.id, self.params["Gripper"].value.id)
        return self.success("picked (world model only)")


class held_place(PrimitiveBase):
    places = 0  # Place calls in this process: the first fails

    def createDescription(self):
        self.setDescription(Place(), "held_place")

    def execute(self):
        type(self).places += 1
        if type(self).places == 1:
            return self.fail("release: gripper fault: EMCY 0x8611: following error (injected)", -1)
        reparent(self.wmi, self.params["Object"].value.id, self.params["Location"].value.id)
        return self.success("placed (world model only)")
