"""Planning in SE(3): the robot turns while it moves (:func:`plan.plan_se3`), every pose and
motion certified by clearance (:class:`clearance.PoseClearance`)."""
