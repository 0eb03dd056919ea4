%
(Pick-and-place cycle on scenario X's machine: the same cycle as pick-place-X.csv)
(Four parts picked at X0 and placed at X400, X300, X200, X100; Z0 is up, Z450 the)
(pick and place height; starts at X0 Z0.  docs/programs.md lists the words.)
N10 G21 G90 G64          ; mm, absolute, G1 moves blend into the next G1 move
(part 1 -> X400)
N20 G0 Z450
N30 G4 P0.2              ; gripper closes
N40 Z0
N50 G1 X200 F30000       ; 30000 mm/min = 0.5 m/s
N60 X400 Z450            ; blends: passes X200 without stopping
N70 G4 P0.15             ; gripper opens
N80 G0 Z0
(part 2 -> X300: back to the pick while Z descends)
N90 X0 Z450
N100 G4 P0.2
N110 Z0
N120 G1 X150
N130 X300 Z450
N140 G4 P0.15
N150 G0 Z0
(part 3 -> X200)
N160 X0 Z450
N170 G4 P0.2
N180 Z0
N190 G1 X100
N200 X200 Z450
N210 G4 P0.15
N220 G0 Z0
(part 4 -> X100, slower, exact stop at the via point)
N230 X0 Z450
N240 G4 P0.2
N250 Z0
N260 G61 G1 X50 F15000
N270 X100 Z450
N280 G4 P0.15
N290 G0 Z0
(home)
N300 X0
N310 M30
%
