#!/bin/bash
# Times the upload of a 200 MB texture on loopback, then kills the server once 100 MB are in
# and shows where the client resumed and how many bytes it sent again (docs/farm.md, Uploads).
B=${LF_BIN:-build/bin}  # run from the repository root after deploy/build.sh
D=$(mktemp -d /tmp/lf_measure.XXXX)
mkdir -p $D/scene
python3 - "$D/scene" <<'PY'
import sys, os, json, struct, zlib, hashlib
d=sys.argv[1]
def chunk(t,data): return struct.pack('>I',len(data))+t+data+struct.pack('>I',zlib.crc32(t+data)&0xffffffff)
png=b'\x89PNG\r\n\x1a\n'+chunk(b'IHDR',struct.pack('>IIBBBBB',2,2,8,2,0,0,0))+chunk(b'IDAT',zlib.compress(b'\x00'+b'\x80'*6+b'\x00'+b'\x80'*6))+chunk(b'IEND',b'')
obj="v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\nf 1/1/1 2/2/1 3/3/1\nf 1/1/1 3/3/1 4/4/1\n"
scene=json.dumps({"camera":{"position":[0.5,0.5,3],"look_at":[0.5,0.5,0],"up":[0,1,0],"fov_y_deg":40,"resolution":[32,32]},
 "materials":{"t":{"type":"lambert","base_color_texture":"tex.png"}},
 "shapes":[{"type":"mesh","file":"quad.obj","material":"t"}],
 "lights":[{"type":"point","position":[0.5,0.5,2],"intensity":[1,1,1]}]})
small=max(hashlib.sha256(obj.encode()).hexdigest(), hashlib.sha256(scene.encode()).hexdigest())
while True:  # the big blob uploads last (by hash), so the line before its "stored" marks its start
    big=png+os.urandom(200*1000*1000)
    if hashlib.sha256(big).hexdigest() > small: break
open(d+'/tex.png','wb').write(big); open(d+'/quad.obj','w').write(obj); open(d+'/scene.json','w').write(scene)
PY
start_server() {
  $B/lightfarm-server --listen $1 --data-dir $D/data --max-scene-mb 1024 > $D/port 2>> $D/server.log &
  SP=$!
  for i in $(seq 100); do grep -q listening $D/port && break; sleep 0.05; done
  ADDR=$(sed 's/listening on //' $D/port)
}
start_server 127.0.0.1:0
echo "== whole upload, server $ADDR"
/usr/bin/time -f "submit: %e s wall" $B/lightfarm submit $D/scene/scene.json --server $ADDR --spp 1 > /dev/null
grep "stored" $D/server.log | cut -c1-200
kill $SP; wait $SP 2>/dev/null
echo "== killed at 50%"
rm -rf $D/data; : > $D/server.log
start_server 127.0.0.1:0
PORTADDR=$ADDR
$B/lightfarm submit $D/scene/scene.json --server $ADDR --spp 1 --retry-seconds 60 > /dev/null 2> $D/client.err &
CP=$!
P=$D/data/blobs/partial
while true; do
  f=$(ls $P 2>/dev/null | head -1)
  if [ -n "$f" ] && [ $(stat -c %s $P/$f) -ge 100000000 ]; then break; fi
  sleep 0.005
done
kill -9 $SP; wait $SP 2>/dev/null
echo "partial at kill: $(stat -c %s $P/$f) bytes"
start_server $PORTADDR
wait $CP; echo "client exit $?"
cat $D/client.err
grep -E "resumes|stored" $D/server.log | cut -c1-220
kill $SP; wait $SP 2>/dev/null
rm -rf $D
