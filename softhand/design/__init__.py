"""Stage 3c: the design search, the paper's future work (issue 38).

Varies the pocketed phalanx (pocket height and span, roof, outer layer) and its two materials
from the library (`softhand.fem.library`) through the FE, scores each design's lifelike
compliance and durability (`softhand.design.evaluate`), keeps the Pareto front of a multi-objective
search (`softhand.design.search`), checks it in 3D and writes a mould's STL per winner
(`softhand.design.outputs`). It uses the FE, the laws' lifelike distance and the sensors'
criteria, the stages to its left.
"""
