// Runs delatin (npm, a JS port of fogleman's hmm) on a raw f64 grid and prints a JSON line.
// usage: node delatin_run.mjs GRID.f64 COLS ROWS MAX_ERROR
// Needs `npm install delatin` in this folder or a parent (not part of the repository).
import Delatin from 'delatin';
import { readFileSync } from 'node:fs';

const [file, cols, rows, maxError] = process.argv.slice(2);
const w = Number(cols), h = Number(rows), e = Number(maxError);
const buf = readFileSync(file);
const data = new Float64Array(buf.buffer, buf.byteOffset, w * h);
const t0 = process.hrtime.bigint();
const tin = new Delatin(data, w, h);
tin.run(e);
const t1 = process.hrtime.bigint();
const cpu = process.cpuUsage();
console.log(JSON.stringify({
  peer: 'delatin',
  points: tin.coords.length / 2,
  triangles: tin.triangles.length / 3,
  max_error: tin.getMaxError(),
  seconds: Number(t1 - t0) / 1e9,
  process_user_seconds: cpu.user / 1e6,
}));
