% The gear model (doc/model.md section 2) and its integrator (section 5: RK4, h = 1 us, stiffness
% switches split out) as a MATLAB user would write it: one column element per realization, a loop
% over time steps, the mesh timing precomputed for all steps at once, normals drawn in chunks.
% Runs in Octave and MATLAB (run by bench/run):
%   gear_octave('params.json', 'out.json', realizations, duration, check_duration, check_every, repeat)
% params.json is `gear_bench params`; out.json gets the same fields as gear_bench's.
function gear_octave(params_file, output_file, realizations, duration, check_duration, check_every, repeat)
  p = jsondecode(fileread(params_file));
  steps = round(duration / p.time_step);
  seconds = zeros(repeat, 1);
  cpu_seconds = zeros(repeat, 1);
  for r = 1:repeat
    randn('state', p.seed);
    tic;
    cpu_start = cputime;
    [d, v] = simulate(p, realizations, steps, true, 0);
    cpu_seconds(r) = cputime - cpu_start;
    seconds(r) = toc;
  end
  every = round(check_every / p.time_step);
  [~, ~, check] = simulate(p, 1, round(check_duration / p.time_step), false, every);
  out = struct('realizations', realizations, 'steps', steps, 'threads', 1, 'check_every', every, ...
               'seconds', seconds, 'cpu_seconds', cpu_seconds, 'delta', d, 'velocity', v, ...
               'check_delta', check(:, 1), 'check_velocity', check(:, 2));
  fid = fopen(output_file, 'w');
  fprintf(fid, '%s\n', jsonencode(out));
  fclose(fid);
end

% Integrates n paths over `steps` grid steps; check holds [delta v] at steps 0, every, 2 every, ...
function [d, v, check] = simulate(p, n, steps, stochastic, every)
  h = p.time_step;
  P = p.mesh_period_angle;
  d = p.initial_deflection * ones(n, 1);
  v = p.initial_velocity * ones(n, 1);
  if stochastic
    load = p.load_mean + p.load_sd * randn(n, 1);
    sigma = p.sigma * sqrt(h);
  else
    load = p.load_mean * ones(n, 1);
    sigma = 0;
  end
  % Mesh timing of every step: K and Q at the stage times, in the midpoint's mesh cycle.
  k = (0:steps - 1)';
  a0 = p.mesh_phase + p.pinion_speed * (k * h);
  a1 = p.mesh_phase + p.pinion_speed * ((k + 1) * h);
  mid = 0.5 * (a0 + a1);
  base = floor(mid / P) * P;
  K = stiffness(p, mid - base);
  Q = p.q3 + p.mu * friction(p, [a0 - base, mid - base, a1 - base]);
  % The next switch after a0; within 1e-9 of a step of a grid point it counts as on it.
  cycle = floor(a0 / P) * P;
  next = cycle + P;
  next(a0 - cycle < p.single_pair_angle) = cycle(a0 - cycle < p.single_pair_angle) + p.single_pair_angle;
  tol = 1e-9 * (a1 - a0);
  split = next > a0 + tol & next < a1 - tol;

  check = [];
  if every > 0
    check = [d(1) v(1)];
  end
  chunk = 4096;
  for i = 1:steps
    if mod(i - 1, chunk) == 0
      z = randn(n, min(chunk, steps - i + 1));
    end
    load1 = load + p.drift * h + sigma * z(:, mod(i - 1, chunk) + 1);
    if split(i)  % two RK4 sub-steps, K and Q frozen at each one's midpoint
      s = next(i);
      ls = load + (s - a0(i)) / (a1(i) - a0(i)) * (load1 - load);
      m = 0.5 * (a0(i) + s);
      lm = m - floor(m / P) * P;
      q = p.q3 + p.mu * friction(p, lm);
      [d, v] = rk4(p, d, v, (s - a0(i)) / (a1(i) - a0(i)) * h, load, ls, stiffness(p, lm), q, q, q);
      m = 0.5 * (s + a1(i));
      lm = m - floor(m / P) * P;
      q = p.q3 + p.mu * friction(p, lm);
      [d, v] = rk4(p, d, v, (a1(i) - s) / (a1(i) - a0(i)) * h, ls, load1, stiffness(p, lm), q, q, q);
    else
      [d, v] = rk4(p, d, v, h, load, load1, K(i), Q(i, 1), Q(i, 2), Q(i, 3));
    end
    load = load1;
    if every > 0 && mod(i, every) == 0
      check(end + 1, :) = [d(1) v(1)];
    end
  end
end

function [d, v] = rk4(p, d, v, H, la, lb, K, qa, qm, qb)
  lm = 0.5 * (la + lb);
  a1 = accel(p, d, v, la, K, qa);
  v2 = v + 0.5 * H * a1;
  a2 = accel(p, d + 0.5 * H * v, v2, lm, K, qm);
  v3 = v + 0.5 * H * a2;
  a3 = accel(p, d + 0.5 * H * v2, v3, lm, K, qm);
  v4 = v + H * a3;
  a4 = accel(p, d + H * v3, v4, lb, K, qb);
  d = d + H / 6 * (v + 2 * v2 + 2 * v3 + v4);
  v = v + H / 6 * (a1 + 2 * a2 + 2 * a3 + a4);
end

% Eq. 15: Phi - Q (K g + alpha |g| v), with g the penetration beyond either flank.
function a = accel(p, d, v, load, K, Q)
  g = d - min(max(d, -p.backlash), p.backlash);
  a = load - Q * (K * g + p.damping_coefficient * abs(g) .* v);
end

function f = friction(p, local_phase)
  f = p.c0 + p.c1 * (p.x_b + p.base_radius1 * local_phase);
end

function K = stiffness(p, local_phase)
  K = p.k2 * ones(size(local_phase));
  K(local_phase < p.single_pair_angle) = p.k1;
end
