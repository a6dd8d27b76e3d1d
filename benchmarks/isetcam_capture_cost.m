% isetcam_capture_cost.m: the per-capture cost of ISETCam's own chain, in
% GNU Octave, on the two captures benchmarks/bench_isetcam_cost.py times on
% ours (issue 49, item 5).  For research only: the project never runs or
% needs Octave or ISETCam (no test does).
%
%   ISETCAM_ROOT=/path/to/isetcam ISETCAM_COST_JSON=out.json ISETCAM_COST_REPEAT=3 \
%     octave --no-gui --norc --quiet benchmarks/isetcam_capture_cost.m
%
% Each scene at the paper's size (docs/scenes.md): 636 x 720 samples x 31
% bands (400:10:700 nm), mean 100 cd/m^2:
%   * macbeth: ISETCam's 'macbeth d65' chart (4 x 6 patches, no surround),
%     nearest-resized to 636 x 720 as the earlier Octave runs did
%     (shared/research/isetcam-octave-timing.md), 30 deg field of view;
%     sensor 636 x 720 pixels (our K = 1).
%   * slanted-edge: an edge 5 deg from vertical, 15 % | 60 % (4:1) under
%     ISETCam's equal-energy illuminant (its 'slanted bar' scene's light),
%     2 deg field of view; sensor 159 x 180 pixels (our K = 4).
% Optics: ISETCam's default diffraction-limited lens at f/4, its focal
% length set so that the sensor's width sees the scene's field of view, as
% ours does.  Sensor: sensorCreate('bayer') (GRBG), 2.2 um pixel, ISETCam's
% default pixel (10 000 e- well, 1 mV read noise, 1 mV/s dark), noise flag 2
% (photon + electronic), auto exposure.  IP: ipCreate, demosaic 'bilinear',
% its default 'MCC optimized' sensor -> XYZ matrix.  Metric: ieISO12233's
% steps (vcGetROIData, ISO12233) on the region our MTF reads, on the edge;
% on the chart the non-plotting steps of macbethColorError
% (chartCornerpoints, ipMCCXYZ, deltaEab to the ideal D65 chart), as in
% shared/research/isetcam-octave-timing.md.
%
% Per capture: oiCompute, sensorCompute, ipCompute and the metric, each timed
% with tic/toc (wall) and cputime, after one warm-up capture (which also
% parses every function); the scene is built once per scene, not timed.
% Prints one line per stage and scene and writes the JSON named by
% ISETCAM_COST_JSON (median seconds of ISETCAM_COST_REPEAT captures).
%
% Shims (written to a temporary folder put first on the path; Debian's
% Octave 7 with octave-image and octave-signal, no statistics package):
% ieInit -> ieInitSession; sensorCheckHuman (Octave's strfind rejects the
% empty name); poissrnd (Knuth's sampler, only for pixels under 25 e-);
% nanmean/nanstd.  The same shims as the parity runs (docs/isetcam-parity.md).

1;

function write_shims(folder)
  shims = struct();
  shims.sensorCheckHuman = { ...
    'function bool = sensorCheckHuman(sensor)', ...
    '  bool = 0; n = sensorGet(sensor, ''name'');', ...
    '  if ischar(n) && ~isempty(strfind(n, ''human'')), bool = 1; return; end', ...
    '  if isfield(sensor, ''human''), bool = 1; end', ...
    'end'};
  shims.poissrnd = { ...
    'function k = poissrnd(lambda)', ...
    '  % Knuth: multiply uniforms until the product falls below exp(-lambda), vectorised', ...
    '  L = exp(-lambda); k = zeros(size(lambda)); p = rand(size(lambda)); live = p > L;', ...
    '  while any(live(:))', ...
    '    k(live) = k(live) + 1; p(live) = p(live) .* rand(nnz(live), 1); live = p > L;', ...
    '  end', ...
    'end'};
  shims.nanmean = { ...
    'function m = nanmean(x, dim)', ...
    '  if nargin < 2, dim = find(size(x) ~= 1, 1); if isempty(dim), dim = 1; end, end', ...
    '  ok = ~isnan(x); x(~ok) = 0; m = sum(x, dim) ./ sum(ok, dim);', ...
    'end'};
  shims.nanstd = { ...
    'function s = nanstd(x, varargin)', ...
    '  if size(x, 1) == 1, x = x(:); end', ...
    '  s = zeros(1, size(x, 2));', ...
    '  for j = 1:size(x, 2), v = x(~isnan(x(:, j)), j); s(j) = std(v); end', ...
    'end'};
  for name = fieldnames(shims)'
    fid = fopen(fullfile(folder, [name{1} '.m']), 'w');
    fprintf(fid, '%s\n', shims.(name{1}){:});
    fclose(fid);
  end
end

function scene = edge_scene(rows, cols, wave, fov_deg)
  % 5 deg from vertical through the centre, dark (15 %) left, bright (60 %) right
  [x, y] = meshgrid((1:cols) - (cols + 1) / 2, (1:rows) - (rows + 1) / 2);
  refl = 0.15 + 0.45 * (x > -y * tand(5));
  scene = sceneCreate('uniform ee', 32, wave);
  il = illuminantCreate('equal energy', wave);
  illP = illuminantGet(il, 'photons');
  photons = bsxfun(@times, refl, reshape(illP, 1, 1, []));
  scene = sceneSet(scene, 'photons', photons);
  scene = sceneSet(scene, 'name', 'slanted edge 5 deg 4:1');
  scene = sceneSet(scene, 'horizontal field of view', fov_deg);
  scene = sceneAdjustLuminance(scene, 100);
end

function scene = macbeth_scene(rows, cols, wave, fov_deg)
  scene = sceneCreate('macbeth d65', 120, wave);  % 480 x 720
  photons = sceneGet(scene, 'photons');
  r = round(linspace(1, size(photons, 1), rows));
  c = round(linspace(1, size(photons, 2), cols));
  scene = sceneSet(scene, 'photons', photons(r, c, :));  % nearest resize to the paper's size
  scene = sceneSet(scene, 'horizontal field of view', fov_deg);
  scene = sceneAdjustLuminance(scene, 100);
end

function v = metric_edge(ip, sensor)
  % ieISO12233's steps with the region given, not searched: ISOFindSlantedBar
  % looks for ISETCam's own bar (bright left, black border) and finds no
  % rectangle on this edge.  The rectangle is our ROI (the render's
  % geometry.roi [128 272 508 448] in scene samples / K = 4): sensor rows
  % 33-127, columns 69-112, as [x y width-1 height-1].
  rect = [69 33 43 94];
  bar = vcGetROIData(ip, rect, 'sensor space');
  bar = reshape(bar, rect(4) + 1, rect(3) + 1, 3);
  mtf = ISO12233(bar, sensorGet(sensor, 'pixel width', 'mm'), [], 'none');
  v = mtf.mtf50;  % cy/mm
end

function v = metric_macbeth(ip, sensor)
  cp = chartCornerpoints(ip, true);  % the chart fills the image
  [xyz, white] = ipMCCXYZ(ip, cp, 'sRGB');
  ideal = macbethIdealColor('d65', 'xyz');
  xyz = (xyz / white(2)) * ideal(4, 2);
  v = mean(deltaEab(xyz, ideal, ideal(4, :)));  % mean dE*ab (1976), macbethColorError's
end

function [t, cpu, value] = one_capture(scene, oi, sensor, ip, metric)
  t = zeros(1, 4); cpu = zeros(1, 4);
  c = cputime; tic; oi = oiCompute(scene, oi); t(1) = toc; cpu(1) = cputime - c;
  c = cputime; tic; sensor = sensorCompute(sensor, oi); t(2) = toc; cpu(2) = cputime - c;
  c = cputime; tic; ip = ipCompute(ip, sensor); t(3) = toc; cpu(3) = cputime - c;
  c = cputime; tic; value = metric(ip, sensor); t(4) = toc; cpu(4) = cputime - c;
end

root = getenv('ISETCAM_ROOT');
if isempty(root), error('isetcam_capture_cost: set ISETCAM_ROOT to an ISETCam checkout'); end
out_json = getenv('ISETCAM_COST_JSON');
repeat = str2double(getenv('ISETCAM_COST_REPEAT'));
if isnan(repeat), repeat = 3; end

shim_dir = tempname(); mkdir(shim_dir); write_shims(shim_dir);
addpath(genpath(root));
addpath(shim_dir);  % first on the path
pkg load image signal
ieInitSession;
setpref('ISET', 'waitbar', 0);
[~, commit] = system(sprintf('git -C "%s" rev-parse HEAD', root)); commit = strtrim(commit);

wave = 400:10:700;
pitch_m = 2.2e-6;
% name, rows, cols, fov (deg), sensor rows, cols (the scene's size / K), metric
specs = {'slanted-edge', 636, 720, 2, 159, 180, @metric_edge; ...
         'macbeth', 636, 720, 30, 636, 720, @metric_macbeth};
stages = {'optics', 'sensor', 'ip', 'metric'};
result = struct('isetcam_commit', commit, 'octave_version', version(), 'repeat', repeat, ...
                'scenes', struct());
for s = 1:rows(specs)
  [name, r, c, fov, sr, sc, metric] = specs{s, :};
  if strcmp(name, 'macbeth'), scene = macbeth_scene(r, c, wave, fov);
  else, scene = edge_scene(r, c, wave, fov); end
  oi = oiCreate('diffraction limited');
  oi = oiSet(oi, 'optics fnumber', 4);
  oi = oiSet(oi, 'optics focal length', (sc * pitch_m / 2) / tand(fov / 2));  % sensor width sees the scene FOV
  sensor = sensorCreate('bayer');
  sensor = sensorSet(sensor, 'pixel size constant fill factor', [pitch_m pitch_m]);
  sensor = sensorSet(sensor, 'size', [sr sc]);
  sensor = sensorSet(sensor, 'auto exposure', true);
  ip = ipCreate;
  ip = ipSet(ip, 'demosaic method', 'bilinear');
  one_capture(scene, oi, sensor, ip, metric);  % warm-up: parses every function once
  walls = zeros(repeat, 4); cpus = zeros(repeat, 4); values = zeros(repeat, 1);
  for k = 1:repeat
    [walls(k, :), cpus(k, :), values(k)] = one_capture(scene, oi, sensor, ip, metric);
  end
  entry = struct('scene_size', [r c numel(wave)], 'sensor_size', [sr sc], 'fov_deg', fov, ...
                 'metric_value', median(values), 'per_capture_s', median(sum(walls, 2)), ...
                 'per_capture_cpu_s', median(sum(cpus, 2)), ...
                 'without_optics_s', median(sum(walls(:, 2:4), 2)), ...
                 'without_optics_cpu_s', median(sum(cpus(:, 2:4), 2)), ...
                 'runs_s', sum(walls, 2)');
  for j = 1:4
    entry.([stages{j} '_s']) = median(walls(:, j));
    entry.([stages{j} '_cpu_s']) = median(cpus(:, j));
    printf('isetcam %-13s %-7s %8.3f s wall %8.3f s cpu\n', name, stages{j}, median(walls(:, j)), median(cpus(:, j)));
  end
  printf('isetcam %-13s %-7s %8.3f s wall %8.3f s cpu (metric %.4g)\n', name, 'capture', entry.per_capture_s, ...
         entry.per_capture_cpu_s, entry.metric_value);
  fflush(stdout);
  result.scenes.(strrep(name, '-', '_')) = entry;
end
if ~isempty(out_json)
  fid = fopen(out_json, 'w'); fprintf(fid, '%s\n', jsonencode(result)); fclose(fid);
end
rmpath(shim_dir); confirm_recursive_rmdir(false); rmdir(shim_dir, 's');
